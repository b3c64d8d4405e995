// libFuzzer harness: the PRT_bundle extension JSON. The input is the extension object's text; the harness puts it
// into a valid bundle with its checksum recomputed (so the fuzzer gets past the checksum to the records) and
// reads that bundle back.
#include "bundle.h"
#include "bundle_internal.h"
#include "fuzz_util.h"

#include <cstring>

namespace {

struct Glb {
    nlohmann::json gltf;
    std::vector<unsigned char> bin;
};

// A bundle with a tetrahedron and one vertex layer, split into its JSON and binary chunks.
const Glb& base() {
    static const Glb glb = [] {
        prt::Bundle bundle;
        bundle.mesh.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
        bundle.mesh.indices = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
        prt::Layer layer;
        layer.name = "transfer";
        layer.domain = "vertex";
        layer.semantic = "sh_transfer_rgb";
        layer.shape = {4, 1, 3};
        layer.data.assign(12, 0.5f);
        bundle.layers.push_back(layer);
        std::string path = prt::fuzz::folder() + "/base.glb";
        prt::writeBundle(path, bundle);
        std::string bytes = prt::readFileBytes(path);
        uint32_t jsonLength, binLength;
        std::memcpy(&jsonLength, bytes.data() + 12, 4);
        std::memcpy(&binLength, bytes.data() + 20 + jsonLength, 4);
        Glb out;
        out.gltf = nlohmann::json::parse(bytes.substr(20, jsonLength));
        const char* bin = bytes.data() + 28 + jsonLength;
        out.bin.assign(bin, bin + binLength);
        return out;
    }();
    return glb;
}

void append32(std::string& out, uint32_t value) { out.append(reinterpret_cast<const char*>(&value), 4); }

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    prt::fuzz::capElements();
    const Glb& glb = base();
    nlohmann::json extension = nlohmann::json::parse(data, data + size, nullptr, false);
    if (extension.is_discarded()) return 0;
    if (extension.is_object()) {
        std::vector<unsigned char> buffer(glb.bin.begin(), glb.bin.begin() + glb.gltf["buffers"][0]["byteLength"].get<size_t>());
        extension["checksum"] = prt::detail::extensionChecksum(buffer, extension);
    }
    nlohmann::json gltf = glb.gltf;
    gltf["extensions"][prt::kBundleExtension] = extension;
    std::string text = gltf.dump();
    text.append((4 - text.size() % 4) % 4, ' ');
    std::string file = "glTF";
    append32(file, 2);
    append32(file, uint32_t(12 + 8 + text.size() + 8 + glb.bin.size()));
    append32(file, uint32_t(text.size()));
    file += "JSON";
    file += text;
    append32(file, uint32_t(glb.bin.size()));
    file += std::string("BIN\0", 4);
    file.append(reinterpret_cast<const char*>(glb.bin.data()), glb.bin.size());
    std::string path = prt::fuzz::writeInput(reinterpret_cast<const uint8_t*>(file.data()), file.size(), "glb");
    prt::fuzz::expectOnlyErrors([&] { prt::readBundle(path); });
    return 0;
}
