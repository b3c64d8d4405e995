// Shared by the libFuzzer harnesses of whole bundles (fuzz_fiv, fuzz_glossy, fuzz_adaptive): a mutated GLB gets
// its PRT_bundle checksum recomputed, so mutations of the extension and the layers reach the layer readers instead
// of stopping at the checksum (as fuzz_bundle does for the extension alone).
#pragma once

#include "bundle.h"
#include "bundle_internal.h"

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace prt::fuzz {

inline uint32_t read32(const uint8_t* p) {
    uint32_t value;
    std::memcpy(&value, p, 4);
    return value;
}

inline void append32(std::string& out, uint32_t value) { out.append(reinterpret_cast<const char*>(&value), 4); }

// The input with its extension checksum recomputed, or as it is when it is not a two-chunk GLB with JSON.
inline std::string withChecksum(const uint8_t* data, size_t size) {
    std::string original(reinterpret_cast<const char*>(data), size);
    if (size < 28 || std::memcmp(data, "glTF", 4) != 0) return original;
    uint32_t jsonLength = read32(data + 12);
    if (jsonLength > size - 28 || std::memcmp(data + 16, "JSON", 4) != 0) return original;
    uint32_t binLength = read32(data + 20 + jsonLength);
    if (binLength > size - 28 - jsonLength) return original;
    nlohmann::json gltf = nlohmann::json::parse(data + 20, data + 20 + jsonLength, nullptr, false);
    if (gltf.is_discarded() || !gltf.is_object() || !gltf.contains("extensions") || !gltf["extensions"].is_object() ||
        !gltf["extensions"].contains(prt::kBundleExtension) || !gltf["extensions"][prt::kBundleExtension].is_object() ||
        !gltf.contains("buffers") || !gltf["buffers"].is_array() || gltf["buffers"].empty() ||
        !gltf["buffers"][0].is_object() || !gltf["buffers"][0].contains("byteLength") ||
        !gltf["buffers"][0]["byteLength"].is_number_unsigned() ||
        gltf["buffers"][0]["byteLength"].get<uint64_t>() > binLength)
        return original;
    const uint8_t* bin = data + 28 + jsonLength;
    std::vector<unsigned char> buffer(bin, bin + gltf["buffers"][0]["byteLength"].get<size_t>());
    nlohmann::json& extension = gltf["extensions"][prt::kBundleExtension];
    extension["checksum"] = prt::detail::extensionChecksum(buffer, extension);
    std::string text = gltf.dump();
    text.append((4 - text.size() % 4) % 4, ' ');
    std::string file = "glTF";
    append32(file, 2);
    append32(file, uint32_t(12 + 8 + text.size() + 8 + binLength));
    append32(file, uint32_t(text.size()));
    file += "JSON";
    file += text;
    append32(file, binLength);
    file += std::string("BIN\0", 4);
    file.append(reinterpret_cast<const char*>(bin), binLength);
    return file;
}

} // namespace prt::fuzz
