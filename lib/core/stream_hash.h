// Content hashing of bytes that arrive in pieces (a file written or read in chunks): the streaming form of
// hashBytes (core.h), for writers and readers that never hold a whole payload.
#pragma once

#include <cstddef>
#include <string>

namespace prt {

// hashBytes over bytes given in pieces: after add(a, n) and add(b, m), digest() is hashBytes of the n + m bytes
// a..b. digest() may be called at any point, each time over everything added so far.
class StreamHash {
public:
    StreamHash();
    ~StreamHash();
    StreamHash(const StreamHash&) = delete;
    StreamHash& operator=(const StreamHash&) = delete;
    void add(const void* data, size_t size);
    std::string digest() const;

private:
    void* state_; // an XXH3_state_t, kept out of this header
};

} // namespace prt
