// (b) The environment reduction: every mask times the cube's radiance into the sample's FIV and occluded power.
#include "fiv.h"

#include "core.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace prt::fiv {

FivGrid reduceVisibility(const Visibility& vis, const CubeEnvironment& env, const std::string& source) {
    size_t samples = vis.grid.sampleCount();
    if (vis.rowBegin != 0 || vis.rowEnd != samples)
        throw Error(source, "fiv", "the reduction needs every grid sample: join the shards first", kExitUsage);
    if (env.size != vis.cube) throw Error(source, "fiv", "environment cube size differs from the masks'", kExitFailure);
    if (vis.offsets.size() != samples + 1 || vis.valid.size() != samples)
        throw Error(source, "fiv_mask_offsets", "does not hold one offset and one valid flag per grid sample");
    CubeTexels cube = cubeTexels(vis.cube);
    size_t texels = cube.solidAngle.size();
    std::vector<double> power(3 * texels), vector(9 * texels); // L dw and L w dw per texel
    for (size_t t = 0; t < texels; ++t)
        for (int c = 0; c < 3; ++c) {
            power[3 * t + c] = env.radiance[3 * t + c] * cube.solidAngle[t];
            for (int a = 0; a < 3; ++a) vector[9 * t + 3 * c + a] = power[3 * t + c] * cube.direction[3 * t + a];
        }
    FivGrid out;
    out.grid = vis.grid;
    out.sphere = vis.sphere;
    out.cube = vis.cube;
    out.supersample = vis.supersample;
    out.fiv.assign(9 * samples, 0.0f);
    out.power.assign(3 * samples, 0.0f);
    out.valid = vis.valid;
    std::vector<double> radii = shellRadii(vis.grid);
    double scale = 1.0 / double(vis.supersample * vis.supersample);
    uint32_t mask = (1u << vis.bitsPerTexel) - 1u;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, samples, 64), [&](const tbb::blocked_range<size_t>& range) {
        std::vector<uint32_t> candidates;
        for (size_t row = range.begin(); row < range.end(); ++row) {
            if (!vis.valid[row]) continue;
            int i = int(row % size_t(vis.grid.azimuth)), j = int(row / size_t(vis.grid.azimuth) % size_t(vis.grid.polar));
            int k = int(row / (size_t(vis.grid.azimuth) * vis.grid.polar));
            double d[3];
            gridDirection(vis.grid, i, j, d);
            candidates.clear();
            candidateTexels(cube, d, radii[size_t(k)], candidates);
            const uint8_t* bits = vis.bits.data() + vis.offsets[row];
            size_t available = 8 * size_t(vis.offsets[row + 1] - vis.offsets[row]);
            if (available < candidates.size() * size_t(vis.bitsPerTexel))
                throw Error(source, "fiv_mask_bits", "row " + std::to_string(row) + " holds " + std::to_string(available) +
                                                         " bits, fewer than its " + std::to_string(candidates.size()) +
                                                         " candidate texels need");
            double fiv[9] = {0}, occluded[3] = {0};
            size_t bit = 0;
            for (uint32_t t : candidates) {
                uint32_t hits = 0;
                for (int b = 0; b < vis.bitsPerTexel; ++b, ++bit) hits |= uint32_t(bits[bit >> 3] >> (bit & 7) & 1u) << b;
                hits &= mask;
                if (!hits) continue;
                double coverage = double(hits) * scale;
                for (int c = 0; c < 3; ++c) occluded[c] += coverage * power[3 * t + c];
                for (int e = 0; e < 9; ++e) fiv[e] += coverage * vector[9 * t + e];
            }
            for (int e = 0; e < 9; ++e) out.fiv[9 * row + e] = float(fiv[e]);
            for (int c = 0; c < 3; ++c) out.power[3 * row + c] = float(occluded[c]);
        }
    });
    return out;
}

} // namespace prt::fiv
