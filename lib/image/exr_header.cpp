// A structural check of an OpenEXR file's headers before OpenImageIO opens it. OpenEXR 3.1 trusts each
// attribute's declared size: a 291-byte file whose string attribute claims 2 GiB makes it allocate that much
// (found by tests/fuzz/fuzz_exr). Here every declared size is bounded by the bytes the file really has, and so are
// the sizes inside the two attribute types that carry their own: a preview image's width x height x 4 bytes, and
// each string of a string vector.
#include "image.h"

#include "core.h"

#include <cstdint>
#include <cstring>
#include <fstream>

namespace prt {

void checkExrHeaders(const std::string& path) {
    std::ifstream in(path, std::ios::binary | std::ios::ate);
    if (!in) return; // the reader reports a missing or unreadable file in its own words
    const uint64_t fileSize = uint64_t(in.tellg());
    in.seekg(0);
    unsigned char start[8];
    if (fileSize < 8 || !in.read(reinterpret_cast<char*>(start), 8)) return;
    static const unsigned char kMagic[4] = {0x76, 0x2f, 0x31, 0x01};
    if (std::memcmp(start, kMagic, 4) != 0) {
        // OpenImageIO would try its other readers on a file named .exr, past this check and the fuzzed path.
        if (fileExtension(path) == "exr")
            throw Error(path, "byte 0", "named .exr but not OpenEXR (no OpenEXR magic number): rename it to its format");
        return; // not OpenEXR: nothing to check here
    }
    const bool multipart = (start[5] & 0x10) != 0;   // version field bit 12
    auto refuse = [&](const std::string& problem) { throw Error(path, "OpenEXR header", problem); };

    uint64_t offset = 8;
    // Reads a null-terminated name of at most 255 characters; returns false at the end of the file.
    auto readName = [&](std::string& name) {
        name.clear();
        for (;;) {
            char c;
            if (!in.get(c)) refuse("truncated: a name runs past the end of the file");
            ++offset;
            if (c == '\0') return;
            if (name.size() == 255) refuse("an attribute name is longer than 255 characters");
            name.push_back(c);
        }
    };
    int headers = 0;
    for (;;) {
        std::string name, type;
        readName(name);
        if (name.empty()) {
            // The end of one header; a multi-part file ends its list of headers with one more empty name.
            ++headers;
            if (!multipart) return;
            int next = in.peek();
            if (next == std::char_traits<char>::eof()) refuse("truncated after header " + std::to_string(headers));
            if (next == 0) return;
            if (headers > 1 << 16) refuse("more than 65536 parts");
            continue;
        }
        readName(type);
        unsigned char sizeBytes[4];
        if (!in.read(reinterpret_cast<char*>(sizeBytes), 4)) refuse("truncated: attribute '" + name + "' has no size");
        offset += 4;
        int32_t size;
        std::memcpy(&size, sizeBytes, 4); // little-endian, as the format and this build are
        if (size < 0 || uint64_t(size) > fileSize - offset)
            refuse("attribute '" + name + "' (" + type + ") declares " + std::to_string(size) + " bytes, but only " +
                   std::to_string(fileSize - offset) + " follow in the file");
        if (type == "preview" || type == "stringvector") {
            std::string value(size_t(size), '\0');
            if (!in.read(value.data(), size)) refuse("truncated: attribute '" + name + "' runs past the end of the file");
            auto word = [&](size_t at) {
                uint32_t v;
                std::memcpy(&v, value.data() + at, 4);
                return v;
            };
            if (type == "preview") {
                if (size < 8) refuse("preview attribute '" + name + "' is shorter than its width and height");
                uint64_t pixels = uint64_t(word(0)) * word(4);
                if (pixels * 4 != uint64_t(size) - 8)
                    refuse("preview attribute '" + name + "' declares " + std::to_string(word(0)) + " x " +
                           std::to_string(word(4)) + " pixels, which its " + std::to_string(size) + " bytes do not hold");
            } else {
                for (size_t at = 0; at < size_t(size);) {
                    if (size_t(size) - at < 4) refuse("string vector attribute '" + name + "' ends inside a length");
                    uint32_t length = word(at);
                    at += 4;
                    if (length > size_t(size) - at)
                        refuse("string vector attribute '" + name + "' holds a string of " + std::to_string(length) +
                               " bytes, more than the attribute's remaining " + std::to_string(size_t(size) - at));
                    at += length;
                }
            }
        }
        offset += uint64_t(size);
        in.seekg(std::streamoff(offset));
    }
}

} // namespace prt
