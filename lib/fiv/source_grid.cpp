// The sources' own grid (issue 20, "FIV under a sharp sun", docs/fiv.md decision 13): per sample of a grid finer
// than the main one, the fraction of the small sources' power the occluder hides, from one ray per source texel.
#include "fiv_internal.h"

#include "core.h"
#include "luminance.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>

namespace prt::fiv {

void checkSourceGrid(const GridSpec& grid, size_t sourceTexels, const std::string& source, int exitCode) {
    try {
        checkGrid(grid, source, exitCode);
    } catch (const Error& e) {
        throw Error(e.file(), "--source-grid", e.problem(), exitCode);
    }
    const uint64_t limit = maxElements() > UINT64_MAX / 16 ? UINT64_MAX : 16 * maxElements();
    // checkGrid caps the samples at 2^26, and the texels of a map are capped by its reader, so this fits 64 bits.
    const uint64_t rays = uint64_t(grid.sampleCount()) * (uint64_t(std::min<size_t>(sourceTexels, 1u << 30)) + 26);
    if (rays > limit)
        throw Error(source, "--source-grid", "samples x (source texels + 26 inside votes) = " + std::to_string(rays) +
                                                 " rays, above the limit of " + std::to_string(limit) +
                                                 " (16 x PRT_MAX_ELEMENTS)",
                    exitCode);
}

SourceGrid sampleSourceGrid(const TriMesh& occluder, const SmallSources& sources, const SourceGridOptions& options,
                            const std::string& source) {
    const size_t texels = sources.direction.size() / 3;
    checkSourceGrid(options.grid, texels, source, kExitUsage);
    if (!(options.sharpen >= kMinSourceSharpen && options.sharpen <= kMaxSourceSharpen))
        throw Error(source, "--source-sharpen", "must lie in " + std::to_string(int(kMinSourceSharpen)) + ".." +
                                                    std::to_string(int(kMaxSourceSharpen)), kExitUsage);
    if (occluder.triangleCount() == 0) throw Error(source, "occluder", "mesh has no triangles", kExitInput);
    if (texels == 0 || sources.power.size() != 3 * texels)
        throw Error(source, "--source-grid", "the map has no small source to give a grid of its own", kExitUsage);
    SourceGrid out;
    out.grid = options.grid;
    out.sphere = boundingSphere(occluder);
    out.sharpen = options.sharpen;
    out.texels = texels;
    for (size_t t = 0; t < texels; ++t)
        for (int c = 0; c < 3; ++c) {
            out.power[size_t(c)] += sources.power[3 * t + size_t(c)];
            for (int a = 0; a < 3; ++a) out.fiv[size_t(3 * c + a)] += sources.power[3 * t + size_t(c)] * sources.direction[3 * t + size_t(a)];
        }
    const double total = kLuminance[0] * out.power[0] + kLuminance[1] * out.power[1] + kLuminance[2] * out.power[2];
    if (!(total > 0.0)) throw Error(source, "--source-grid", "the small sources carry no power", kExitUsage);

    const size_t samples = options.grid.sampleCount(), azimuth = size_t(options.grid.azimuth);
    const std::vector<double> radii = shellRadii(options.grid);
    out.fraction.assign(samples, 0.0f);
    out.valid.assign(samples, 0);
    std::atomic<uint64_t> sourceRays{0}, insideRays{0};
    tbb::task_arena arena(arenaConcurrency(options.threads));
    arena.execute([&] {
        Tracer tracer(occluder);
        const size_t lines = samples / azimuth;
        Progress progress("fiv source grid", lines);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, lines, 1), [&](const tbb::blocked_range<size_t>& range) {
            SourceScratch scratch;
            uint64_t cast = 0, votes = 0;
            for (size_t line = range.begin(); line < range.end(); ++line) {
                size_t j = line % size_t(options.grid.polar);
                bool pole = j == 0 || j + 1 == size_t(options.grid.polar);
                // Every azimuth of a pole row is the same sample: traced once, copied.
                for (size_t row = line * azimuth; row < (line + 1) * azimuth; ++row) {
                    if (pole && row > line * azimuth) {
                        out.fraction[row] = out.fraction[line * azimuth], out.valid[row] = out.valid[line * azimuth];
                        continue;
                    }
                    double d[3], toCentre[3], fiv[9], hidden[3];
                    float origin[3];
                    double rho = receiverPoint(out.grid, out.sphere, radii, row, d, toCentre, origin);
                    if (rho < 1.0 && tracer.inside(origin, votes)) continue; // valid 0, fraction 0
                    out.valid[row] = 1;
                    cast += traceSources(tracer, sources, origin, toCentre, rho, out.sphere.radius, scratch, fiv, hidden);
                    double l = kLuminance[0] * hidden[0] + kLuminance[1] * hidden[1] + kLuminance[2] * hidden[2];
                    out.fraction[row] = float(std::clamp(l / total, 0.0, 1.0));
                }
            }
            sourceRays += cast;
            insideRays += votes;
            progress.add(range.size());
        });
        progress.finish();
    });
    out.sourceRays = sourceRays;
    out.insideRays = insideRays;
    return out;
}

} // namespace prt::fiv
