// libFuzzer harness: glossy bundles (`prt glossy`) through their layer reader. The input is a whole GLB; when its
// JSON parses, the harness recomputes the PRT_bundle checksum (fuzz_glb.h), reads the bundle and the lobes
// (glossyModel), then runs what `prt relight --eye` and `prt render` run on them on a tiny 8x4 map: the glossy
// radiance of every vertex toward two eyes and toward a few directions of one vertex. Seeds: tests/fuzz/corpus/glossy/
// (an icosahedron with 1 and 2 lobes per view).
#include "bundle.h"
#include "fuzz_glb.h"
#include "fuzz_util.h"
#include "runtime.h"

#include <algorithm>
#include <cmath>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    prt::fuzz::capElements();
    std::string file = prt::fuzz::withChecksum(data, size);
    std::string path = prt::fuzz::writeInput(reinterpret_cast<const uint8_t*>(file.data()), file.size(), "glb");
    prt::fuzz::expectOnlyErrors([&] {
        prt::Bundle bundle = prt::readBundle(path);
        prt::GlossyModel model = prt::glossyModel(bundle, path);
        // The shading costs vertices x view triangles x lobes x map texels: only when that fits a fuzzer's time limit.
        if (size_t(model.vertexCount) * (model.triangles.size() / 3) > 200'000) return;
        std::vector<float> map(8 * 4 * 3);
        for (size_t i = 0; i < map.size(); ++i) map[i] = float(i % 7) * 0.25f;
        prt::PrefilteredEnvironment env = prt::prefilterEnvironment(map.data(), 8, 4);
        std::vector<float> radiance(size_t(model.vertexCount) * 3);
        const float eyes[][3] = {{0, 0, 3}, {1, 2, -2}};
        for (const auto& eye : eyes) prt::glossyRadiance(model, env, eye, radiance.data());
        const float directions[][3] = {{0, 1, 0}, {0.6f, 0, 0.8f}, {0, 0, -1}, {-0.48f, -0.6f, 0.64f}};
        for (uint32_t v = 0; v < std::min<uint32_t>(model.vertexCount, 4); ++v)
            for (const auto& d : directions) {
                float out[3];
                prt::glossyRadianceToward(model, env, v, d, out);
            }
    });
    return 0;
}
