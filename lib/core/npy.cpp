#include "core.h"

#include <cstdio>
#include <cstring>
#include <string>

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
    std::string header = bytes.substr(offset, headerLength);
    if (header.find("'<f4'") == std::string::npos) throw Error(path, "header", "dtype must be float32 ('<f4')");
    if (header.find("'fortran_order': False") == std::string::npos) throw Error(path, "header", "Fortran order is not supported");
    size_t open = header.find('(', header.find("'shape'")), close = header.find(')', open);
    if (open == std::string::npos || close == std::string::npos) throw Error(path, "header", "no shape");
    std::vector<size_t> dims;
    std::vector<uint64_t> extents;
    for (size_t i = open + 1; i < close;) {
        while (i < close && (header[i] == ' ' || header[i] == ',')) ++i;
        if (i >= close) break;
        // Digits only: std::stoull would accept signs and throw on anything else.
        uint64_t n = 0;
        size_t digits = 0;
        for (; i < close && header[i] >= '0' && header[i] <= '9'; ++i, ++digits) {
            if (n > (UINT64_MAX - 9) / 10) throw Error(path, "header", "shape extent is too large");
            n = n * 10 + uint64_t(header[i] - '0');
        }
        if (digits == 0) throw Error(path, "header", "shape holds something other than non-negative integers");
        if (dims.size() >= 32) throw Error(path, "header", "shape has more than 32 dimensions");
        dims.push_back(size_t(n));
        extents.push_back(n);
    }
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
