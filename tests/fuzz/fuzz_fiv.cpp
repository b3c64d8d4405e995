// libFuzzer harness: FIV bundles (`prt fiv`, `prt fiv-visibility`, `prt fivscene`) through their layer readers. The
// input is a whole GLB; when its JSON parses, the harness recomputes the PRT_bundle checksum (so mutations of the
// extension reach the layer readers, as fuzz_bundle does), reads the bundle, then runs what `prt fiv` and `prt
// fivshade` run on it: readVisibility and the reduction, or fivScene / fivOccluder and fivLighting, then the
// shading at a few points. Seeds: tests/fuzz/corpus/fiv/ (a FIV grid, a visibility bundle, a scene).
#include "bundle.h"
#include "bundle_internal.h"
#include "fiv.h"
#include "fuzz_util.h"
#include "runtime.h"

#include <cstring>

namespace {

uint32_t read32(const uint8_t* p) {
    uint32_t value;
    std::memcpy(&value, p, 4);
    return value;
}

void append32(std::string& out, uint32_t value) { out.append(reinterpret_cast<const char*>(&value), 4); }

// The input with its extension checksum recomputed, or as it is when it is not a two-chunk GLB with JSON.
std::string withChecksum(const uint8_t* data, size_t size) {
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

// Shading at a few points around the origin, as fivshade does; every value must come out finite.
void shade(const prt::FivLighting& lighting, const std::vector<prt::FivInstance>& instances, const prt::FivInstance* self) {
    const float positions[] = {0, 0, 0, 0.3f, -0.2f, 0.1f, 2, 1, -1, 0, 5, 0};
    const float normals[] = {0, 1, 0, 0.6f, 0.8f, 0, 0, 0, -1, 1, 0, 0};
    float irradiance[12];
    prt::fivIrradiance(lighting, instances.data(), instances.size(), self, positions, normals, 4, {}, irradiance);
    for (float v : irradiance)
        if (!std::isfinite(v)) std::abort();
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    prt::fuzz::capElements();
    std::string file = withChecksum(data, size);
    std::string path = prt::fuzz::writeInput(reinterpret_cast<const uint8_t*>(file.data()), file.size(), "glb");
    prt::fuzz::expectOnlyErrors([&] {
        prt::Bundle bundle = prt::readBundle(path);
        if (prt::findLayer(bundle, "fiv_mask_offsets")) {
            prt::fiv::Visibility vis = prt::fiv::readVisibility(bundle, path);
            // The reduction of a whole grid, when it is small enough for a fuzzer's time limit.
            if (vis.rowBegin == 0 && vis.rowEnd == vis.grid.sampleCount() &&
                vis.grid.sampleCount() * 6 * size_t(vis.cube) * vis.cube <= 4'000'000) {
                prt::fiv::CubeEnvironment env;
                env.size = vis.cube;
                env.radiance.assign(3 * 6 * size_t(vis.cube) * vis.cube, 1.0);
                prt::fiv::reduceVisibility(vis, env, path);
            }
        } else if (prt::isFivScene(bundle)) {
            prt::FivScene scene = prt::fivScene(bundle, path);
            shade(scene.lighting, scene.instances, scene.selfShadowing ? &scene.self : nullptr);
        } else {
            prt::FivOccluder occluder = prt::fivOccluder(bundle, path);
            prt::FivLighting lighting = prt::fivLighting(bundle, path);
            shade(lighting, {{&occluder, {0, 1, 0}}, {&occluder, {0.5f, 1.5f, 0}}}, nullptr);
        }
    });
    return 0;
}
