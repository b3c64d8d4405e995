// Reads a bundle without its layers' values (bundle_stream.h): one pass over the file in 1 MiB pieces that hashes
// the whole binary chunk and keeps the bytes before the first layer view; tinygltf then reads a .glb made of the
// JSON and those bytes alone, and readBundle's own code (bundleFromModel) checks and describes everything.
#include "bundle_internal.h"

#include "json_input.h"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <memory>

namespace prt {

using nlohmann::json;

namespace {

constexpr size_t kPiece = 1 << 20;

[[noreturn]] void refuse(const std::string& path, const std::string& problem) { throw Error(path, "glTF binary", problem, kExitInput); }

uint64_t unsignedMember(const json& object, const char* key, uint64_t fallback, const std::string& path, const std::string& place) {
    if (!object.is_object() || !object.contains(key)) return fallback;
    if (!object[key].is_number_unsigned()) refuse(path, place + "." + key + " is not a non-negative integer");
    return object[key].get<uint64_t>();
}

void readAt(std::ifstream& in, uint64_t offset, void* data, size_t size, const std::string& path) {
    in.seekg(std::streamoff(offset));
    in.read(static_cast<char*>(data), std::streamsize(size));
    if (!in) refuse(path, "cannot read " + std::to_string(size) + " bytes at " + std::to_string(offset) + " (the file changed?)");
}

// The views the PRT_bundle layers use, by index; malformed records are left to bundleFromModel to refuse.
std::vector<size_t> layerViews(const json& gltf, size_t viewCount) {
    std::vector<size_t> views;
    if (!gltf.contains("extensions") || !gltf["extensions"].is_object() || !gltf["extensions"].contains(kBundleExtension))
        return views;
    const json& extension = gltf["extensions"][kBundleExtension];
    if (!extension.is_object() || !extension.contains("layers") || !extension["layers"].is_array()) return views;
    for (const json& layer : extension["layers"])
        if (layer.is_object() && layer.contains("bufferView") && layer["bufferView"].is_number_unsigned() &&
            layer["bufferView"].get<uint64_t>() < viewCount)
            views.push_back(layer["bufferView"].get<size_t>());
    std::sort(views.begin(), views.end());
    views.erase(std::unique(views.begin(), views.end()), views.end());
    return views;
}

} // namespace

BundleHeader readBundleHeader(const std::string& path) {
    std::error_code error;
    const uint64_t fileSize = std::filesystem::file_size(path, error);
    std::ifstream in(path, std::ios::binary);
    if (error || !in) throw Error(path, "", "cannot read (missing?)", kExitInput);
    uint32_t head[5] = {0, 0, 0, 0, 0}; // magic, version, length, JSON chunk length, JSON chunk type
    if (fileSize < sizeof head) refuse(path, "too short for a .glb");
    readAt(in, 0, head, sizeof head, path);
    if (std::memcmp(head, "glTF", 4) != 0) refuse(path, "not a .glb: a bundle is streamed from a glTF binary only");
    detail::checkGlbHeader(path, head[1], head[2], fileSize);
    const uint64_t length = head[2], jsonLength = head[3], binaryStart = 28 + jsonLength;
    if (head[4] != 0x4E4F534Au || binaryStart > length) refuse(path, "has no JSON chunk followed by a BIN chunk");
    std::string text(jsonLength, '\0');
    readAt(in, 20, text.data(), text.size(), path);
    uint32_t binaryHead[2] = {0, 0};
    readAt(in, 20 + jsonLength, binaryHead, sizeof binaryHead, path);
    if (binaryHead[1] != 0x004E4942u || binaryStart + binaryHead[0] > length) refuse(path, "BIN chunk is missing or reaches past the file");

    checkJsonShape(text, path, "glTF binary", std::numeric_limits<unsigned int>::max());
    json gltf = json::parse(text, nullptr, false);
    if (!gltf.is_object()) refuse(path, "JSON chunk is malformed");
    if (!gltf.contains("buffers") || !gltf["buffers"].is_array() || gltf["buffers"].size() != 1 || !gltf["buffers"][0].is_object() ||
        gltf["buffers"][0].contains("uri"))
        refuse(path, "has not exactly one buffer, the BIN chunk (as prt writes bundles)");
    const uint64_t bufferLength = unsignedMember(gltf["buffers"][0], "byteLength", 0, path, "buffers[0]");
    if (bufferLength > binaryHead[0]) refuse(path, "buffers[0] is longer than the BIN chunk");

    // The layer views must come after every other view: the bytes before the first (the meshes, an asset's
    // buffers and images) are all tinygltf needs.
    const json views = gltf.value("bufferViews", json::array());
    if (!views.is_array()) refuse(path, "bufferViews is not an array");
    std::vector<size_t> layers = layerViews(gltf, views.size());
    std::vector<bool> isLayer(views.size(), false);
    for (size_t v : layers) isLayer[v] = true;
    uint64_t prefix = bufferLength, otherEnd = 0;
    struct Span { uint64_t begin, end; };
    std::vector<Span> spans(views.size());
    for (size_t v = 0; v < views.size(); ++v) {
        std::string place = "bufferViews[" + std::to_string(v) + "]";
        uint64_t begin = unsignedMember(views[v], "byteOffset", 0, path, place);
        uint64_t size = unsignedMember(views[v], "byteLength", 0, path, place);
        if (begin > bufferLength || size > bufferLength - begin) refuse(path, place + " reaches past the end of its buffer");
        spans[v] = {begin, begin + size};
        if (isLayer[v]) prefix = std::min(prefix, begin);
        else otherEnd = std::max(otherEnd, begin + size);
    }
    if (otherEnd > prefix)
        refuse(path, "a layer's bytes lie before a mesh's or the asset's: not laid out as prt writes bundles, so it cannot be "
                     "streamed (rewrite it with a prt stage)");
    if (prefix == 0) refuse(path, "holds no mesh bytes before its layers");

    // A .glb of the JSON (buffer 0 cut to the bytes before the layers) and those bytes, for tinygltf; the pass below
    // reads the bytes straight into it, so the mesh bytes are held once before tinygltf copies them.
    json cut = gltf;
    cut["buffers"][0]["byteLength"] = prefix;
    std::string cutText = cut.dump();
    cut = json();
    cutText.resize((cutText.size() + 3) / 4 * 4, ' ');
    const uint64_t paddedPrefix = (prefix + 3) / 4 * 4;
    const uint32_t glbHead[5] = {0x46546C67u, 2u, uint32_t(12 + 8 + cutText.size() + 8 + paddedPrefix), uint32_t(cutText.size()),
                                 0x4E4F534Au};
    const uint32_t glbBinary[2] = {uint32_t(paddedPrefix), 0x004E4942u};
    std::string glb(reinterpret_cast<const char*>(glbHead), sizeof glbHead);
    glb.append(cutText);
    glb.append(reinterpret_cast<const char*>(glbBinary), sizeof glbBinary);
    cutText = {};
    const size_t prefixStart = glb.size();
    glb.resize(prefixStart + paddedPrefix, '\0');

    // One pass over buffer 0: hashed whole (the checksum) and per layer view; the bytes before the layers kept.
    StreamHash whole;
    std::map<std::pair<uint64_t, uint64_t>, std::unique_ptr<StreamHash>> viewHashes;
    for (size_t v : layers) viewHashes.try_emplace({spans[v].begin, spans[v].end - spans[v].begin}, std::make_unique<StreamHash>());
    std::vector<char> piece(kPiece);
    for (uint64_t at = 0; at < bufferLength; at += kPiece) {
        size_t size = size_t(std::min<uint64_t>(kPiece, bufferLength - at));
        readAt(in, binaryStart + at, piece.data(), size, path);
        whole.add(piece.data(), size);
        if (at < prefix) std::memcpy(glb.data() + prefixStart + at, piece.data(), size_t(std::min<uint64_t>(size, prefix - at)));
        for (auto& [view, hash] : viewHashes) {
            uint64_t begin = std::max(view.first, at), end = std::min(view.first + view.second, at + size);
            if (begin < end) hash->add(piece.data() + (begin - at), end - begin);
        }
    }
    std::string ignored;
    tinygltf::Model model = detail::loadModelFromBytes(path, glb, ignored);
    glb = {};

    BundleHeader header;
    header.path = path;
    detail::StreamedBuffer streamed{bufferLength, &whole, &header.extents};
    header.bundle = detail::bundleFromModel(std::move(model), std::move(text), path, &streamed);
    for (LayerExtent& extent : header.extents) {
        if (extent.byteLength == 0) continue;
        auto found = viewHashes.find({extent.offset, extent.byteLength});
        if (found == viewHashes.end()) refuse(path, "a layer's view was not streamed"); // cannot happen: the same views
        extent.hash = found->second->digest();
        extent.offset += binaryStart;
    }
    return header;
}

void streamLayerBytes(const BundleHeader& header, size_t index, const ByteSink& sink) {
    const Layer& layer = header.bundle.layers.at(index);
    const LayerExtent& extent = header.extents.at(index);
    const std::string place = "layer " + layer.name;
    if (extent.byteLength == 0) return;
    std::ifstream in(header.path, std::ios::binary);
    in.seekg(std::streamoff(extent.offset));
    StreamHash hash;
    std::vector<char> piece(size_t(std::min<uint64_t>(kPiece, extent.byteLength)));
    for (uint64_t at = 0; at < extent.byteLength; at += kPiece) {
        size_t size = size_t(std::min<uint64_t>(kPiece, extent.byteLength - at));
        in.read(piece.data(), std::streamsize(size));
        if (!in) throw Error(header.path, place, "cannot be read (the file changed since it was checked?)", kExitInput);
        hash.add(piece.data(), size);
        sink(piece.data(), size);
    }
    if (hash.digest() != extent.hash)
        throw Error(header.path, place, "changed since the bundle's checksum was checked: its bytes are not those hashed",
                    kExitInput);
}

void readLayerFloats(const BundleHeader& header, size_t index, float* values) {
    const Layer& layer = header.bundle.layers.at(index);
    if (layer.componentType != "float32" && layer.componentType != "float16")
        throw Error(header.path, "layer " + layer.name, "holds " + layer.componentType + ", not floats", kExitInput);
    const bool half = layer.componentType == "float16";
    uint64_t done = 0; // bytes decoded; pieces come in whole values (1 MiB each but the last, an even count)
    streamLayerBytes(header, index, [&](const void* bytes, size_t size) {
        if (!half) {
            std::memcpy(reinterpret_cast<char*>(values) + done, bytes, size);
        } else {
            const unsigned char* b = static_cast<const unsigned char*>(bytes);
            for (size_t i = 0; i + 1 < size; i += 2) values[(done + i) / 2] = halfToFloat(uint16_t(b[i] | (b[i + 1] << 8)));
        }
        done += size;
    });
}

void readLayerValues(const BundleHeader& header, size_t index, Layer& layer) {
    const std::string& type = header.bundle.layers.at(index).componentType;
    const size_t size = detail::componentSize(type);
    // The validator checked the view against the shape and the type; a layer without a view (params.uri, whose type
    // it does not check) has no bytes here, and stays empty as readBundle leaves it.
    const uint64_t bytes = header.extents.at(index).byteLength, count = bytes == 0 ? 0 : bytes / size;
    if (detail::isFloatComponent(type)) {
        layer.data.resize(count);
        readLayerFloats(header, index, layer.data.data());
        return;
    }
    layer.integers.resize(count);
    uint64_t done = 0; // values decoded; pieces come in whole values (1 MiB each but the last)
    streamLayerBytes(header, index, [&](const void* bytes, size_t bytesInPiece) {
        detail::decodeIntegers(static_cast<const unsigned char*>(bytes), bytesInPiece / size, size,
                               layer.integers.data() + done);
        done += bytesInPiece / size;
    });
}

} // namespace prt
