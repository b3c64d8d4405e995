#include "core.h"
#include "utf8.h"

#include <cstdio>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

namespace prt {

namespace {

// A version 1.0 .npy of `dtype` ("<f4", "|u1") and `shape` holding `payloadBytes` bytes of row-major data, atomic.
void writeNpyBytes(const std::string& path, const char* dtype, const void* payload, size_t payloadBytes,
                   size_t elementBytes, const std::vector<size_t>& shape) {
    size_t count = 1;
    for (size_t n : shape) count *= n;
    if (count * elementBytes != payloadBytes)
        throw Error(path, "", "internal: npy shape does not match data size", kExitFailure);
    std::string shapeText = "(";
    for (size_t i = 0; i < shape.size(); ++i) shapeText += std::to_string(shape[i]) + (shape.size() == 1 || i + 1 < shape.size() ? "," : "");
    shapeText += ")";
    std::string header = std::string("{'descr': '") + dtype + "', 'fortran_order': False, 'shape': " + shapeText + ", }";
    // Version 1.0: magic(6) + version(2) + header length(2) + header padded with spaces to a multiple of 64, '\n'.
    size_t total = 10 + header.size() + 1;
    header.append((64 - total % 64) % 64, ' ');
    header += '\n';
    std::string bytes("\x93NUMPY\x01\x00", 8);
    uint16_t headerLength = uint16_t(header.size());
    bytes.append(reinterpret_cast<const char*>(&headerLength), 2);
    bytes += header;
    bytes.append(reinterpret_cast<const char*>(payload), payloadBytes);
    writeBytesAtomic(path, bytes);
}

// The header dict of a .npy, as numpy writes it: {'descr': STRING, 'fortran_order': True|False, 'shape': (N, ...)},
// each key exactly once, in any order, an optional trailing comma, then spaces and a newline. Anything else is
// refused (a reader that searched the text for '<f4' took {'descr': '>f4', 'x': '<f4'} for float32).
struct NpyHeader {
    std::string descr;
    bool fortranOrder = false;
    std::vector<size_t> shape;
};

NpyHeader parseNpyHeader(std::string_view text, const std::string& path) {
    size_t i = 0;
    auto fail = [&](const std::string& problem) -> Error {
        return Error(path, "header, byte " + std::to_string(i), problem);
    };
    auto skipSpaces = [&] {
        while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
    };
    auto expect = [&](char c) {
        skipSpaces();
        if (i >= text.size() || text[i] != c) throw fail(std::string("expected '") + c + "'");
        ++i;
    };
    auto quoted = [&] {
        skipSpaces();
        if (i >= text.size() || (text[i] != '\'' && text[i] != '"')) throw fail("expected a quoted string");
        const char quote = text[i++];
        const size_t begin = i;
        while (i < text.size() && text[i] != quote) {
            if (text[i] == '\\' || uint8_t(text[i]) < 0x20) throw fail("unexpected byte in a string");
            ++i;
        }
        if (i >= text.size()) throw fail("unterminated string");
        return std::string(text.substr(begin, i++ - begin));
    };
    NpyHeader header;
    bool seenDescr = false, seenOrder = false, seenShape = false;
    expect('{');
    for (;;) {
        skipSpaces();
        if (i < text.size() && text[i] == '}') break;
        const std::string key = quoted();
        expect(':');
        skipSpaces();
        if (key == "descr" && !seenDescr) {
            header.descr = quoted();
            seenDescr = true;
        } else if (key == "fortran_order" && !seenOrder) {
            if (text.substr(i, 4) == "True") header.fortranOrder = true, i += 4;
            else if (text.substr(i, 5) == "False") header.fortranOrder = false, i += 5;
            else throw fail("fortran_order must be True or False");
            seenOrder = true;
        } else if (key == "shape" && !seenShape) {
            expect('(');
            for (;;) {
                skipSpaces();
                if (i < text.size() && text[i] == ')') break;
                // Digits only: std::stoull would accept signs and throw on anything else.
                uint64_t n = 0;
                size_t digits = 0;
                for (; i < text.size() && text[i] >= '0' && text[i] <= '9'; ++i, ++digits) {
                    if (n > (UINT64_MAX - 9) / 10) throw fail("shape extent is too large");
                    n = n * 10 + uint64_t(text[i] - '0');
                }
                if (digits == 0) throw fail("shape holds something other than non-negative integers");
                if (header.shape.size() >= 32) throw fail("shape has more than 32 dimensions");
                header.shape.push_back(size_t(n));
                skipSpaces();
                if (i < text.size() && text[i] == ',') ++i;
                else if (i >= text.size() || text[i] != ')') throw fail("expected ',' or ')' in the shape");
            }
            ++i; // ')'
            seenShape = true;
        } else {
            throw fail("unexpected or repeated key '" + printableBytes(key, 40) + "'");
        }
        skipSpaces();
        if (i < text.size() && text[i] == ',') ++i;
        else if (i >= text.size() || text[i] != '}') throw fail("expected ',' or '}'");
    }
    ++i; // '}'
    while (i < text.size() && (text[i] == ' ' || text[i] == '\n')) ++i;
    if (i != text.size()) throw fail("unexpected bytes after the header dict");
    if (!seenDescr || !seenOrder || !seenShape) throw fail("the header lacks 'descr', 'fortran_order' or 'shape'");
    return header;
}

} // namespace

void writeNpy(const std::string& path, const std::vector<float>& data, const std::vector<size_t>& shape) {
    writeNpyBytes(path, "<f4", data.data(), data.size() * sizeof(float), sizeof(float), shape);
}

void writeNpyU8(const std::string& path, const std::vector<uint8_t>& data, const std::vector<size_t>& shape) {
    writeNpyBytes(path, "|u1", data.data(), data.size(), 1, shape);
}

std::vector<float> readNpy(const std::string& path, std::vector<size_t>* shape) {
    std::string bytes = readFileBytes(path);
    if (bytes.size() < 10 || bytes.compare(0, 6, "\x93NUMPY") != 0) throw Error(path, "header", "not a .npy file");
    unsigned major = (unsigned char)bytes[6];
    size_t headerLength, offset;
    if (major == 1) {
        headerLength = (unsigned char)bytes[8] | (unsigned char)bytes[9] << 8;
        offset = 10;
    } else if (major == 2 || major == 3) {
        if (bytes.size() < 12) throw Error(path, "header", "truncated");
        headerLength = (unsigned char)bytes[8] | (unsigned char)bytes[9] << 8 | (unsigned char)bytes[10] << 16 |
                       size_t((unsigned char)bytes[11]) << 24;
        offset = 12;
    } else {
        throw Error(path, "header", "unsupported .npy version " + std::to_string(major));
    }
    if (bytes.size() < offset + headerLength) throw Error(path, "header", "truncated");
    NpyHeader header = parseNpyHeader(std::string_view(bytes).substr(offset, headerLength), path);
    if (header.descr != "<f4")
        throw Error(path, "header", "dtype must be little-endian float32 ('<f4'), found '" + printableBytes(header.descr, 40) + "'");
    if (header.fortranOrder) throw Error(path, "header", "Fortran order is not supported");
    const std::vector<size_t>& dims = header.shape;
    std::vector<uint64_t> extents(dims.begin(), dims.end());
    uint64_t count = checkedProduct(extents, "floats", path, "header shape");
    size_t dataOffset = offset + headerLength;
    if ((bytes.size() - dataOffset) % sizeof(float) != 0 || (bytes.size() - dataOffset) / sizeof(float) != count)
        throw Error(path, "data", "expected " + std::to_string(count) + " floats, file holds " +
                                      std::to_string((bytes.size() - dataOffset) / sizeof(float)));
    std::vector<float> data(count);
    if (count > 0) std::memcpy(data.data(), bytes.data() + dataOffset, count * sizeof(float)); // memcpy of null is UB
    if (shape) *shape = dims;
    return data;
}

} // namespace prt
