// libFuzzer harness: FIV bundles (`prt fiv`, `prt fiv-visibility`, `prt fivscene`) through their layer readers. The
// input is a whole GLB; when its JSON parses, the harness recomputes the PRT_bundle checksum (so mutations of the
// extension reach the layer readers, as fuzz_bundle does), reads the bundle, then runs what `prt fiv` and `prt
// fivshade` run on it: readVisibility and the reduction, or fivScene / fivOccluder and fivLighting, then the
// shading at a few points. Seeds: tests/fuzz/corpus/fiv/ (a FIV grid, one with the fiv_self layer, one with fiv_self
// and the sources' own grid (fiv_source_grid, fiv_source_valid), a visibility bundle, a scene, and a scene whose
// receiver and occluder carry the source grid and fiv_self).
#include "bundle.h"
#include "bundle_internal.h"
#include "fiv.h"
#include "fuzz_glb.h"
#include "fuzz_util.h"
#include "runtime.h"

#include <cstring>

namespace {

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
    std::string file = prt::fuzz::withChecksum(data, size);
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
