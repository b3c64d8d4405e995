#include "core.h"
#include "stream_hash.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <new>
#include <vector>
// Header-only xxHash (XXH_INLINE_ALL): the digest code compiles into prt_core, so nothing that links prt (the
// installed runtime included) needs libxxhash at run time.
#define XXH_INLINE_ALL
#include <xxhash.h>

namespace prt {

static std::string hexDigest(XXH128_hash_t hash) {
    char text[40];
    std::snprintf(text, sizeof(text), "%016llx%016llx", (unsigned long long)hash.high64,
                  (unsigned long long)hash.low64);
    return std::string("xxh128:") + text;
}

std::string hashBytes(const void* data, size_t size) { return hexDigest(XXH3_128bits(data, size)); }

std::string hashFile(const std::string& path) {
    std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), std::fclose);
    if (!file) throw Error(path, "", std::string("cannot open: ") + std::strerror(errno));
    std::unique_ptr<XXH3_state_t, XXH_errorcode (*)(XXH3_state_t*)> state(XXH3_createState(), XXH3_freeState);
    XXH3_128bits_reset(state.get());
    std::vector<char> chunk(1 << 20);
    size_t got;
    while ((got = std::fread(chunk.data(), 1, chunk.size(), file.get())) > 0) XXH3_128bits_update(state.get(), chunk.data(), got);
    if (std::ferror(file.get())) throw Error(path, "", "read failed");
    return hexDigest(XXH3_128bits_digest(state.get()));
}

StreamHash::StreamHash() : state_(XXH3_createState()) {
    if (!state_) throw std::bad_alloc();
    XXH3_128bits_reset(static_cast<XXH3_state_t*>(state_));
}

StreamHash::~StreamHash() { XXH3_freeState(static_cast<XXH3_state_t*>(state_)); }

void StreamHash::add(const void* data, size_t size) {
    if (size > 0) XXH3_128bits_update(static_cast<XXH3_state_t*>(state_), data, size);
}

std::string StreamHash::digest() const { return hexDigest(XXH3_128bits_digest(static_cast<XXH3_state_t*>(state_))); }

} // namespace prt
