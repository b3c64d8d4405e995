// (a) Visibility: per grid sample, which cube texels the occluder hides, by Embree rays from the receiver point.
// Only texels whose cone reaches the bounding sphere are candidates, and only subsample rays that meet the sphere
// are cast; the rest are unoccluded by construction.
#include "fiv_internal.h"

#include "core.h"
#include "mesh.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

namespace prt::fiv {

namespace {

struct BitWriter {
    std::vector<uint8_t>& out;
    int used = 8; // bits used in the last byte
    void put(uint32_t value, int bits) {
        for (int b = 0; b < bits; ++b) {
            if (used == 8) out.push_back(0), used = 0;
            if (value >> b & 1u) out.back() |= uint8_t(1u << used);
            ++used;
        }
    }
};

// Per-thread buffers of sampleMask: the sample's candidates, and its rays with the candidate each belongs to.
struct MaskScratch {
    std::vector<uint32_t> candidates;
    std::vector<RTCRay> rays;
    std::vector<uint32_t> rayCandidate;
    std::vector<uint32_t> hits;
};

// One sample's mask bytes; returns false when the receiver is inside the occluder. Every ray of a sample leaves
// one point towards one sphere, so they go to Embree as one coherent stream (rtcOccluded1M), which traces them
// in packets.
bool sampleMask(const Tracer& tracer, const CubeTexels& cube, const Visibility& vis, const std::vector<double>& radii,
                size_t row, MaskScratch& scratch, std::vector<uint8_t>& bytes, uint64_t& rays) {
    double d[3], toCentre[3];
    float origin[3];
    double rho = receiverPoint(vis.grid, vis.sphere, radii, row, d, toCentre, origin), radius = vis.sphere.radius;
    if (rho < 1.0 && tracer.inside(origin, rays)) return false;
    std::vector<uint32_t>& candidates = scratch.candidates;
    candidates.clear();
    candidateTexels(cube, d, rho, candidates);
    int s = vis.supersample;
    scratch.rays.clear();
    scratch.rayCandidate.clear();
    for (uint32_t c = 0; c < candidates.size(); ++c)
        for (int sy = 0; sy < s; ++sy)
            for (int sx = 0; sx < s; ++sx) {
                double w[3];
                subsampleDirection(cube, candidates[c], sx, sy, s, w);
                if (!canMeetSphere(toCentre, rho, radius, w)) continue;
                float wf[3] = {float(w[0]), float(w[1]), float(w[2])};
                scratch.rays.push_back(makeRay(origin, wf));
                scratch.rayCandidate.push_back(c);
            }
    if (!scratch.rays.empty()) {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
        rtcOccluded1M(tracer.embree.scene, &context, scratch.rays.data(), unsigned(scratch.rays.size()), sizeof(RTCRay));
    }
    rays += scratch.rays.size();
    scratch.hits.assign(candidates.size(), 0);
    for (size_t r = 0; r < scratch.rays.size(); ++r)
        if (scratch.rays[r].tfar < 0.0f) ++scratch.hits[scratch.rayCandidate[r]];
    BitWriter writer{bytes};
    for (uint32_t hits : scratch.hits) writer.put(hits, vis.bitsPerTexel);
    return true;
}

} // namespace

int bitsPerTexel(int supersample) {
    int levels = supersample * supersample + 1, bits = 1;
    while ((1 << bits) < levels) ++bits;
    return bits;
}

void candidateTexels(const CubeTexels& cube, const double d[3], double rho, std::vector<uint32_t>& out) {
    size_t count = cube.solidAngle.size();
    if (rho <= 1.0) {
        for (size_t t = 0; t < count; ++t) out.push_back(uint32_t(t));
        return;
    }
    double sinAlpha = 1.0 / rho, cosAlpha = std::sqrt(1.0 - sinAlpha * sinAlpha);
    for (size_t t = 0; t < count; ++t) {
        const double* w = &cube.direction[3 * t];
        double cosine = d[0] * w[0] + d[1] * w[1] + d[2] * w[2];
        // angle(w, d) <= alpha + radius, i.e. cos(angle) >= cos(alpha + radius) while alpha + radius < pi.
        double limit = cosAlpha * cube.cosRadius[t] - sinAlpha * cube.sinRadius[t];
        if (cosine >= limit) out.push_back(uint32_t(t));
    }
}

Visibility sampleVisibility(const TriMesh& occluder, const VisibilityOptions& options, const std::string& source) {
    checkGrid(options.grid, source, kExitUsage);
    if (options.supersample < 1 || options.supersample > kMaxSupersample)
        throw Error(source, "--supersample", "must lie in 1.." + std::to_string(kMaxSupersample), kExitUsage);
    if (options.shardCount < 1 || options.shardIndex < 0 || options.shardIndex >= options.shardCount)
        throw Error(source, "--shard", "needs 0 <= I < N", kExitUsage);
    if (occluder.triangleCount() == 0) throw Error(source, "occluder", "mesh has no triangles", kExitInput);
    CubeTexels cube = cubeTexels(options.cube);
    checkWork(options.grid, options.cube, options.supersample, source, kExitUsage);

    Visibility vis;
    vis.grid = options.grid;
    vis.cube = options.cube;
    vis.supersample = options.supersample;
    vis.bitsPerTexel = bitsPerTexel(options.supersample);
    vis.sphere = boundingSphere(occluder);
    vis.shardIndex = options.shardIndex;
    vis.shardCount = options.shardCount;
    MeshTopology topology = analyzeTopology(occluder);
    vis.boundaryEdges = topology.boundaryEdges + topology.nonManifoldEdges;
    vis.closed = vis.boundaryEdges == 0;
    if (!vis.closed && !options.allowOpen)
        throw Error(source, "occluder",
                    "is not closed (" + std::to_string(topology.boundaryEdges) + " boundary edges in " +
                        std::to_string(topology.boundaryLoops) + " loops, " +
                        std::to_string(topology.nonManifoldEdges) +
                        " non-manifold edges): telling samples inside the occluder from outside needs a closed "
                        "surface; --allow-open decides by a majority vote of back-face hits instead",
                    kExitInput);
    if (!vis.closed)
        logWarn(source + ": occluder is open (" + std::to_string(vis.boundaryEdges) +
                " boundary edges); inside samples are decided by a back-face vote of 26 rays");

    size_t samples = options.grid.sampleCount();
    RowRange range = shardRows(samples, options.shardIndex, options.shardCount);
    vis.rowBegin = range.begin;
    vis.rowEnd = range.end;
    size_t rows = range.end - range.begin;
    vis.naiveRays = uint64_t(rows) * cube.solidAngle.size() * uint64_t(options.supersample * options.supersample);
    std::vector<double> radii = shellRadii(options.grid);
    size_t azimuth = size_t(options.grid.azimuth);
    size_t firstLine = range.begin / azimuth, endLine = rows ? (range.end - 1) / azimuth + 1 : firstLine;

    std::vector<std::vector<uint8_t>> bytes(rows);
    vis.valid.assign(rows, 0);
    std::atomic<uint64_t> rays{0};
    tbb::task_arena arena(arenaConcurrency(options.threads));
    arena.execute([&] {
        Tracer tracer(occluder);
        Progress progress("fiv visibility", endLine - firstLine);
        tbb::parallel_for(tbb::blocked_range<size_t>(firstLine, endLine, 1), [&](const tbb::blocked_range<size_t>& r) {
            MaskScratch scratch;
            uint64_t lineRays = 0;
            for (size_t line = r.begin(); line < r.end(); ++line) {
                size_t j = line % size_t(options.grid.polar);
                bool pole = j == 0 || j + 1 == size_t(options.grid.polar);
                size_t lo = std::max(line * azimuth, range.begin), hi = std::min((line + 1) * azimuth, range.end);
                if (pole) { // every azimuth of a pole row is the same sample: compute it once, copy it
                    // Its rays count where its first row lies, so shards sum to the unsharded count.
                    std::vector<uint8_t> poleBytes;
                    uint64_t poleRays = 0;
                    bool valid = sampleMask(tracer, cube, vis, radii, line * azimuth, scratch, poleBytes, poleRays);
                    if (line * azimuth >= range.begin) lineRays += poleRays;
                    for (size_t row = lo; row < hi; ++row) {
                        bytes[row - range.begin] = valid ? poleBytes : std::vector<uint8_t>();
                        vis.valid[row - range.begin] = valid;
                    }
                } else {
                    for (size_t row = lo; row < hi; ++row) {
                        std::vector<uint8_t>& out = bytes[row - range.begin];
                        bool valid = sampleMask(tracer, cube, vis, radii, row, scratch, out, lineRays);
                        if (!valid) out.clear();
                        vis.valid[row - range.begin] = valid;
                    }
                }
            }
            rays += lineRays;
            progress.add(r.size());
        });
        progress.finish();
    });
    vis.rays = rays;

    uint64_t total = 0;
    for (const auto& b : bytes) total += b.size();
    if (total > std::numeric_limits<uint32_t>::max())
        throw Error(source, "--grid", "masks exceed 4 GiB; use a coarser grid or shards", kExitUsage);
    vis.offsets.resize(rows + 1);
    vis.bits.reserve(size_t(total));
    for (size_t r = 0; r < rows; ++r) {
        vis.offsets[r] = uint32_t(vis.bits.size());
        vis.bits.insert(vis.bits.end(), bytes[r].begin(), bytes[r].end());
        std::vector<uint8_t>().swap(bytes[r]);
    }
    vis.offsets[rows] = uint32_t(vis.bits.size());
    return vis;
}

uint64_t addSourceShadows(const TriMesh& occluder, const Visibility& vis, const SmallSources& sources, FivGrid& grid,
                          int threads) {
    const size_t samples = vis.grid.sampleCount(), texels = sources.direction.size() / 3;
    if (texels == 0) return 0;
    if (grid.fiv.size() != 9 * samples || grid.power.size() != 3 * samples || vis.valid.size() != samples ||
        vis.rowBegin != 0 || vis.rowEnd != samples)
        throw Error("", "fiv", "source shadows need the whole grid reduced from its visibility", kExitFailure);
    const std::vector<double> radii = shellRadii(vis.grid);
    std::atomic<uint64_t> rays{0};
    tbb::task_arena arena(arenaConcurrency(threads));
    arena.execute([&] {
        Tracer tracer(occluder);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, samples, 256), [&](const tbb::blocked_range<size_t>& range) {
            SourceScratch scratch;
            uint64_t cast = 0;
            for (size_t row = range.begin(); row < range.end(); ++row) {
                if (!vis.valid[row]) continue;
                double d[3], toCentre[3], fiv[9], occluded[3];
                float origin[3];
                double rho = receiverPoint(vis.grid, vis.sphere, radii, row, d, toCentre, origin);
                uint64_t traced = traceSources(tracer, sources, origin, toCentre, rho, vis.sphere.radius, scratch, fiv, occluded);
                if (traced == 0) continue;
                cast += traced;
                for (int e = 0; e < 9; ++e) grid.fiv[9 * row + size_t(e)] = float(double(grid.fiv[9 * row + size_t(e)]) + fiv[e]);
                for (int c = 0; c < 3; ++c)
                    grid.power[3 * row + size_t(c)] = float(double(grid.power[3 * row + size_t(c)]) + occluded[c]);
            }
            rays += cast;
        });
    });
    return rays;
}

Visibility joinShards(std::vector<Visibility> shards, const std::vector<std::string>& files) {
    if (shards.empty()) throw Error("", "fiv", "no visibility given", kExitUsage);
    std::vector<size_t> order(shards.size(), size_t(-1));
    int count = shards[0].shardCount;
    for (size_t s = 0; s < shards.size(); ++s) {
        const Visibility& v = shards[s];
        const Visibility& first = shards[0];
        if (v.shardCount != count || int(shards.size()) != count)
            throw Error(files[s], "fiv_mask_offsets", "is shard of " + std::to_string(v.shardCount) + ", but " +
                                                          std::to_string(shards.size()) + " were given");
        if (v.grid.azimuth != first.grid.azimuth || v.grid.polar != first.grid.polar ||
            v.grid.shells != first.grid.shells || v.grid.shellMin != first.grid.shellMin ||
            v.grid.shellMax != first.grid.shellMax || v.cube != first.cube || v.supersample != first.supersample ||
            v.sphere.radius != first.sphere.radius)
            throw Error(files[s], "fiv_mask_offsets", "belongs to another run than " + files[0]);
        if (v.shardIndex < 0 || v.shardIndex >= count || order[size_t(v.shardIndex)] != size_t(-1))
            throw Error(files[s], "fiv_mask_offsets", "shard " + std::to_string(v.shardIndex) + " repeats or is out of range");
        order[size_t(v.shardIndex)] = s;
    }
    Visibility joined = std::move(shards[order[0]]);
    for (int index = 1; index < count; ++index) {
        Visibility& part = shards[order[size_t(index)]];
        if (part.rowBegin != joined.rowEnd)
            throw Error(files[order[size_t(index)]], "fiv_mask_offsets", "rows do not follow the previous shard");
        uint64_t base = joined.bits.size();
        if (base + part.bits.size() > std::numeric_limits<uint32_t>::max())
            throw Error(files[order[size_t(index)]], "fiv_mask_bits", "joined masks exceed 4 GiB");
        joined.offsets.pop_back();
        for (uint32_t offset : part.offsets) joined.offsets.push_back(uint32_t(base + offset));
        joined.bits.insert(joined.bits.end(), part.bits.begin(), part.bits.end());
        joined.valid.insert(joined.valid.end(), part.valid.begin(), part.valid.end());
        joined.rowEnd = part.rowEnd;
        joined.rays += part.rays;
        joined.naiveRays += part.naiveRays;
    }
    joined.shardIndex = 0;
    joined.shardCount = 1;
    return joined;
}

} // namespace prt::fiv
