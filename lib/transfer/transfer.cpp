// Diffuse SH transfer per vertex or per receiver (texel): one direct pass of rays, then Jacobi Neumann bounces
// (thesis Fig. 4.2) that gather the previous bounce at the direct pass's recorded hits instead of casting new rays.
#include "transfer.h"

#include "core.h"
#include "material.h"
#include "passes.h"
#include "rays.h"
#include "sh.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <ctime>
#include <numbers>
#include <optional>

namespace prt {

TransferMode parseTransferMode(const std::string& name) {
    if (name == "unshadowed") return TransferMode::Unshadowed;
    if (name == "shadowed") return TransferMode::Shadowed;
    if (name == "interreflected") return TransferMode::Interreflected;
    throw Error("", "--mode", "'" + name + "' is not one of unshadowed, shadowed, interreflected", kExitUsage);
}

const char* transferModeName(TransferMode mode) {
    switch (mode) {
    case TransferMode::Unshadowed: return "unshadowed";
    case TransferMode::Shadowed: return "shadowed";
    case TransferMode::Interreflected: return "interreflected";
    }
    return "?";
}

namespace passes {

// Checks the options and the mesh's own albedo (the vertex range is the caller's business).
void checkOptions(const TriMesh& mesh, const TransferOptions& options) {
    auto usage = [](const std::string& place, const std::string& problem) {
        return Error("", place, problem, kExitUsage);
    };
    if (options.order < 1 || options.order > sh::kMaxOrder)
        throw usage("order", std::to_string(options.order) + " outside 1.." + std::to_string(sh::kMaxOrder));
    if (options.mode != TransferMode::Unshadowed &&
        (options.samples < 1 || options.samples > kMaxTransferSamples))
        throw usage("samples", std::to_string(options.samples) + " outside 1.." +
                                   std::to_string(kMaxTransferSamples));
    if (options.bounces < 0) throw usage("bounces", "must be >= 0");
    if (options.bounces > 0 && options.mode != TransferMode::Interreflected)
        throw usage("bounces", "need mode interreflected");
    for (float a : options.albedo)
        if (!(a >= 0.0f && a <= 1.0f)) throw usage("albedo", "components must lie in [0, 1]");
    if (options.surface && options.albedoOverride) throw usage("albedo", "a scene's materials give the albedo");
    if (options.surface && options.surface->mesh->triangleCount() != mesh.triangleCount())
        throw usage("surface", "belongs to another mesh");
    if (!mesh.albedo.empty() && !options.albedoOverride)
        for (size_t i = 0; i < mesh.albedo.size(); ++i)
            if (!(mesh.albedo[i] >= 0.0f && mesh.albedo[i] <= 1.0f))
                throw Error("", "vertex " + std::to_string(i / 3), "albedo outside [0, 1]");
}

Context makeContext(const TriMesh& mesh, const TransferOptions& options, const Receivers& receivers) {
    Context context{mesh, options, receivers, options.order * options.order, 3 * options.order * options.order,
                    rayOffset(mesh), {}, {}, {}, {}};
    int n = options.order * options.order;
    context.lambert.resize(n);
    for (int l = 0; l < options.order; ++l)
        for (int m = -l; m <= l; ++m) context.lambert[sh::index(l, m)] = sh::clampedCosine(l) / std::numbers::pi;
    if (options.mode == TransferMode::Unshadowed) return context;

    int samples = options.samples;
    context.directions = rays::hemisphere(samples);
    context.weightedBasis.resize(size_t(samples) * n);
    context.cosines.resize(samples);
    std::vector<double> basis(n);
    for (int k = 0; k < samples; ++k) {
        const rays::Hemisphere& d = context.directions;
        double cosine = (k + 0.5) / samples;
        sh::evaluate(options.order, double(d.x[k]), double(d.y[k]), double(d.z[k]), basis.data());
        for (int j = 0; j < n; ++j) context.weightedBasis[size_t(k) * n + j] = float(cosine * basis[j]);
        context.cosines[k] = float(cosine);
    }
    return context;
}

namespace {

// Per-unit-albedo direct transfer of one receiver in world coordinates, t_j = (1/pi) integral V cos Y_j:
// the exact unshadowed part A_l/pi Y_j(n) minus (2/N) times the occluded samples' sum rotated out of the local
// frame. `occluded` is that sum in the local frame; `anyOccluded` false skips the rotation (the sum is zero).
// Writes albedo * t to `row` ([order^2][3]) and, when `unitRow` is not null, t itself ([order^2]).
void directRow(const Context& context, const rays::Fan& fan, const std::vector<double>& occluded, bool anyOccluded,
               size_t receiver, std::vector<double>& scratch, float* row, float* unitRow) {
    int n = context.coefficients, order = context.options.order;
    scratch.resize(2 * size_t(n));
    double* normalBasis = scratch.data();
    double* rotated = scratch.data() + n;
    sh::evaluate(order, fan.normal[0], fan.normal[1], fan.normal[2], normalBasis);
    std::fill(rotated, rotated + n, 0.0);
    if (anyOccluded) {
        // Columns tangent, bitangent, normal: maps local directions to world ones.
        const double frame[9] = {fan.tangent[0], fan.bitangent[0], fan.normal[0],
                                 fan.tangent[1], fan.bitangent[1], fan.normal[1],
                                 fan.tangent[2], fan.bitangent[2], fan.normal[2]};
        sh::rotate(sh::rotation(order, frame), occluded.data(), rotated, 1);
    }
    double weight = 2.0 / context.options.samples;
    std::array<float, 3> albedo = context.albedo(receiver);
    for (int j = 0; j < n; ++j) {
        double transfer = context.lambert[j] * normalBasis[j] - weight * rotated[j];
        for (int c = 0; c < 3; ++c) row[3 * j + c] = float(albedo[c] * transfer);
        if (unitRow) unitRow[j] = float(transfer);
    }
}

uint32_t quantiseBarycentric(float w) { return uint32_t(std::lround(std::clamp(w, 0.0f, 1.0f) * 65535.0f)); }

// Casts one receiver's rays: occlusion rays, or nearest-hit rays when `hits` is not null, whose front-face hits are
// appended to `hits` and back-face hits counted in `backFaceHits`. Adds the weighted local basis of every
// occluded sample to `occluded`; returns whether there was any.
bool traceVertex(const Context& context, const EmbreeScene& scene, const rays::Fan& fan,
                 RTCIntersectContext& intersectContext, std::vector<double>& occluded, HitBlock* hits,
                 uint64_t& backFaceHits) {
    int n = context.coefficients;
    bool anyOccluded = false;
    for (int k = 0; k < context.options.samples; ++k) {
        RTCRayHit rayHit;
        rays::setRay(fan, context.directions, k, context.offset, rayHit.ray);
        bool blocked;
        if (!hits) {
            rtcOccluded1(scene.scene, &intersectContext, &rayHit.ray);
            blocked = rayHit.ray.tfar < 0.0f;
        } else {
            rayHit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
            rtcIntersect1(scene.scene, &intersectContext, &rayHit);
            blocked = rayHit.hit.geomID != RTC_INVALID_GEOMETRY_ID;
            // Embree's triangle Ng is (v1 - v0) x (v2 - v0), on the counter-clockwise front side; an instance's is in
            // its object's space, so the flattened triangle's own is taken there.
            const RTCHit& hit = rayHit.hit;
            const uint32_t triangle = blocked ? scene.flatTriangle(hit) : 0;
            float ng[3] = {hit.Ng_x, hit.Ng_y, hit.Ng_z};
            if (blocked && scene.instanced()) triangleNormal(context.mesh, triangle, ng);
            float facing = ng[0] * rayHit.ray.dir_x + ng[1] * rayHit.ray.dir_y + ng[2] * rayHit.ray.dir_z;
            if (blocked && facing > 0.0f) {
                ++backFaceHits;
            } else if (blocked) {
                hits->triangle.push_back(triangle);
                hits->barycentric.push_back(quantiseBarycentric(hit.u) | quantiseBarycentric(hit.v) << 16);
                hits->sample.push_back(uint16_t(k));
            }
        }
        if (blocked) {
            anyOccluded = true;
            const float* weighted = &context.weightedBasis[size_t(k) * n];
            for (int j = 0; j < n; ++j) occluded[j] += weighted[j];
        }
    }
    return anyOccluded;
}

} // namespace

void directPass(const Context& context, const EmbreeScene& scene, float* out, float* unitOut,
                std::vector<HitBlock>* hitBlocks, DirectCounts& counts, Progress* progress) {
    int n = context.coefficients;
    const size_t receiverCount = context.receivers.count;
    size_t blockCount = (receiverCount + rays::kBlockVertices - 1) / rays::kBlockVertices;

    tbb::parallel_for(tbb::blocked_range<size_t>(0, blockCount, 1), [&](const tbb::blocked_range<size_t>& blocks) {
        std::vector<double> occluded(n), scratch;
        RTCIntersectContext intersectContext;
        rtcInitIntersectContext(&intersectContext);
        for (size_t block = blocks.begin(); block != blocks.end(); ++block) {
            size_t first = block * rays::kBlockVertices;
            size_t last = std::min(first + rays::kBlockVertices, receiverCount);
            HitBlock* hits = hitBlocks ? &(*hitBlocks)[block] : nullptr;
            uint64_t backFaceHits = 0;
            for (size_t v = first; v < last; ++v) {
                rays::Fan fan = rays::fan(context.receivers, v, context.options.seed, context.offset);
                std::fill(occluded.begin(), occluded.end(), 0.0);
                bool anyOccluded = traceVertex(context, scene, fan, intersectContext, occluded, hits, backFaceHits);
                if (hits) hits->end.push_back(uint32_t(hits->triangle.size()));
                directRow(context, fan, occluded, anyOccluded, v, scratch, out + v * context.stride,
                          unitOut ? unitOut + v * n : nullptr);
            }
            if (hits) {
                hits->triangle.shrink_to_fit();
                hits->barycentric.shrink_to_fit();
                hits->sample.shrink_to_fit();
                counts.hits += hits->triangle.size();
            }
            counts.rays += uint64_t(last - first) * context.options.samples;
            counts.backFaceHits += backFaceHits;
            if (progress) progress->add(last - first);
        }
    });
}

namespace {

// What bounce() fixes for all its vertices.
struct BounceTerms {
    int channels = 1;
    size_t rowFloats = 0;            // floats per row of `previous` and `next`: order^2 * channels
    float weight = 0.0f;             // 2 / N
    float power[3] = {1.0f, 1.0f, 1.0f}; // albedo^(number + 1) per channel (channels 1)
};

// Rows of hit triangles are scattered over the mesh: bounceVertex fetches them a few hits ahead (and their corner
// indices further ahead) so the memory latency overlaps the arithmetic.
constexpr size_t kRowsAhead = 8, kCornersAhead = 16;
void prefetchRows(const uint32_t* cornerRows, const float* previous, size_t rowFloats, uint32_t triangle) {
    const size_t rowBytes = rowFloats * sizeof(float);
    const uint32_t* corner = &cornerRows[3 * size_t(triangle)];
    for (int k = 0; k < 3; ++k) {
        const char* row = reinterpret_cast<const char*>(previous + corner[k] * rowFloats);
        for (size_t byte = 0; byte < rowBytes; byte += 64) __builtin_prefetch(row + byte);
        __builtin_prefetch(row + rowBytes - 1);
    }
}

// The per-vertex body of bounce(): vertex i of `hits` (row v of `next` and `total`), whose hits are [h, end).
// Sums `previous` at each hit, in the order recorded, into `sum`, scales it by 2/N (and the albedo) into `light`,
// adds that to the total row and stores it in the next row. Every path that bounces a vertex, the whole mesh or a
// shard, goes through here, so the floats match bit for bit. Corner k of triangle t reads row cornerRows[3 t + k]
// of `previous`.
void bounceVertex(const Context& context, const BounceTerms& terms, const HitBlock& hits, size_t h, size_t end,
                  size_t v, const float* previous, const uint32_t* cornerRows, float* next, float* total,
                  float* __restrict sum, float* __restrict light) {
    const size_t rowFloats = terms.rowFloats, hitCount = hits.triangle.size();
    if (h == end) {
        // Nothing to gather: leaves `total` untouched to the bit (adding +0 would flip -0).
        if (next) std::fill(next + v * rowFloats, next + (v + 1) * rowFloats, 0.0f);
        return;
    }
    std::fill(sum, sum + rowFloats, 0.0f);
    for (; h < end; ++h) {
        if (h + kCornersAhead < hitCount)
            __builtin_prefetch(&cornerRows[3 * size_t(hits.triangle[h + kCornersAhead])]);
        if (h + kRowsAhead < hitCount) prefetchRows(cornerRows, previous, rowFloats, hits.triangle[h + kRowsAhead]);
        const uint32_t* corner = &cornerRows[3 * size_t(hits.triangle[h])];
        const float* __restrict a = previous + size_t(corner[0]) * rowFloats;
        const float* __restrict b = previous + size_t(corner[1]) * rowFloats;
        const float* __restrict c = previous + size_t(corner[2]) * rowFloats;
        float cosine = context.cosines[hits.sample[h]];
        float wb = cosine * float(hits.barycentric[h] & 0xFFFFu) * (1.0f / 65535.0f);
        float wc = cosine * float(hits.barycentric[h] >> 16) * (1.0f / 65535.0f);
        float wa = cosine - wb - wc;
        if (context.options.surface) {
            // The hit reflects its irradiance times its own albedo (rowFloats = order^2 * 3).
            std::array<float, 3> rho = diffuseAlbedoAt(*context.options.surface, hits.triangle[h],
                                                       float(hits.barycentric[h] & 0xFFFFu) * (1.0f / 65535.0f),
                                                       float(hits.barycentric[h] >> 16) * (1.0f / 65535.0f));
            for (size_t x = 0; x < rowFloats; ++x) sum[x] += rho[x % 3] * (wa * a[x] + wb * b[x] + wc * c[x]);
            continue;
        }
        for (size_t x = 0; x < rowFloats; ++x) sum[x] += wa * a[x] + wb * b[x] + wc * c[x];
    }
    float* totalRow = total + v * context.stride;
    if (terms.channels == 3) {
        std::array<float, 3> albedo = context.albedo(v);
        for (size_t x = 0; x < rowFloats; ++x) light[x] = sum[x] * (albedo[x % 3] * terms.weight);
        for (size_t x = 0; x < rowFloats; ++x) totalRow[x] += light[x];
    } else {
        for (size_t x = 0; x < rowFloats; ++x) light[x] = sum[x] * terms.weight;
        for (size_t j = 0; j < rowFloats; ++j)
            for (int c = 0; c < 3; ++c) totalRow[3 * j + c] += terms.power[c] * light[j];
    }
    if (next) std::copy(light, light + rowFloats, next + v * rowFloats);
}

} // namespace

void bounce(const Context& context, const std::vector<HitBlock>& hitBlocks, int channels, const float* previous,
            const uint32_t* cornerRows, float* next, float* total, int number, Progress* progress) {
    BounceTerms terms;
    terms.channels = channels;
    terms.rowFloats = size_t(context.coefficients) * channels;
    terms.weight = 2.0f / float(context.options.samples);
    for (int c = 0; c < 3; ++c)
        for (int b = 0; b <= number; ++b) terms.power[c] *= context.options.albedo[c];

    tbb::blocked_range<size_t> allBlocks(0, hitBlocks.size(), 1);
    tbb::parallel_for(allBlocks, [&](const tbb::blocked_range<size_t>& blocks) {
        std::vector<float> gathered(terms.rowFloats), light(terms.rowFloats);
        for (size_t block = blocks.begin(); block != blocks.end(); ++block) {
            const HitBlock& hits = hitBlocks[block];
            const size_t hitCount = hits.triangle.size(), first = block * rays::kBlockVertices;
            for (size_t h = 0; h < std::min(kRowsAhead, hitCount); ++h)
                prefetchRows(cornerRows, previous, terms.rowFloats, hits.triangle[h]);
            size_t h = 0;
            for (size_t i = 0; i < hits.end.size(); ++i) {
                bounceVertex(context, terms, hits, h, hits.end[i], first + i, previous, cornerRows, next, total,
                             gathered.data(), light.data());
                h = hits.end[i];
            }
            if (progress) progress->add(hits.end.size());
        }
    });
}

namespace {

// The closed form (albedo/pi) A_l Y_lm(n) for every receiver: directRow with nothing occluded. Returns its seconds.
double unshadowedPass(const Context& context, float* out) {
    double start = nowSeconds();
    tbb::blocked_range<size_t> receivers(0, context.receivers.count, rays::kBlockVertices);
    tbb::parallel_for(receivers, [&](const tbb::blocked_range<size_t>& range) {
        std::vector<double> none(context.coefficients, 0.0), scratch;
        for (size_t v = range.begin(); v != range.end(); ++v) {
            rays::Fan fan = rays::fan(context.receivers, v, context.options.seed, context.offset);
            directRow(context, fan, none, false, v, scratch, out + v * context.stride, nullptr);
        }
    });
    return nowSeconds() - start;
}

std::optional<Progress> maybeProgress(const TransferOptions& options, const std::string& label, size_t total) {
    std::optional<Progress> progress;
    if (options.progress) progress.emplace(label, total);
    return progress;
}

void finish(std::optional<Progress>& progress) {
    if (progress) progress->finish();
}

} // namespace

uint64_t hitRecordBytes(const std::vector<HitBlock>& blocks) {
    uint64_t bytes = 0;
    for (const HitBlock& block : blocks) bytes += block.end.size() * 4 + block.triangle.size() * 10;
    return bytes;
}

void runDirectPass(const Context& context, float* out, float* unitOut, std::vector<HitBlock>* hitBlocks,
                   TransferStats& stats) {
    DirectCounts counts;
    double start = nowSeconds();
    {
        EmbreeScene scene(context.mesh, context.options.surface);
        stats.buildSeconds = nowSeconds() - start;
        start = nowSeconds();
        std::clock_t cpuStart = std::clock();
        std::optional<Progress> progress =
            maybeProgress(context.options, hitBlocks ? "transfer direct pass (hits recorded)" : "transfer direct pass",
                          context.receivers.count);
        directPass(context, scene, out, unitOut, hitBlocks, counts, progress ? &*progress : nullptr);
        finish(progress);
        stats.directCpuSeconds = double(std::clock() - cpuStart) / CLOCKS_PER_SEC;
        stats.directSeconds = nowSeconds() - start;
    }
    stats.rays = counts.rays;
    stats.hits = counts.hits;
    stats.backFaceHits = counts.backFaceHits;
    if (hitBlocks) stats.hitRecordBytes = hitRecordBytes(*hitBlocks);
}

} // namespace passes

using namespace passes;

Transfer computeTransfer(const TriMesh& mesh, const TransferOptions& options) {
    rays::validateMesh(mesh);
    size_t begin, end;
    rays::clipRange(mesh, options, begin, end);
    checkOptions(mesh, options);
    if (options.bounces > 0 && (begin != 0 || end != mesh.vertexCount()))
        throw Error("", "vertex range", "interreflected bounces gather from every vertex, so they need the whole mesh",
                    kExitUsage);
    const std::vector<float> spawn = spawnNormals(mesh, begin, end);
    Context context = makeContext(mesh, options, rays::vertexReceivers(mesh, options, begin, end, spawn.data()));

    Transfer result;
    result.order = options.order;
    result.vertexBegin = begin;
    result.vertexEnd = end;
    TransferStats& stats = result.stats;
    stats.rayOffset = context.offset;
    std::vector<float>& total = result.coefficients;
    total.resize((end - begin) * context.stride);
    stats.transferBytes = total.size() * sizeof(float);

    tbb::task_arena arena(arenaConcurrency(options.threads));
    arena.execute([&] {
        if (options.mode == TransferMode::Unshadowed) {
            stats.directSeconds = unshadowedPass(context, total.data());
            return;
        }
        bool interreflected = options.mode == TransferMode::Interreflected;
        int channels = bounceChannels(mesh, options); // one albedo: bounces run on one channel (see bounce())
        bool unitRows = interreflected && options.bounces > 0 && channels == 1;
        std::vector<float> previous(unitRows ? (end - begin) * context.coefficients : 0);
        std::vector<HitBlock> hitBlocks(interreflected ? hitBlockCount(end - begin) : 0);
        runDirectPass(context, total.data(), unitRows ? previous.data() : nullptr, interreflected ? &hitBlocks : nullptr,
                      stats);
        if (options.bounces == 0) return;
        if (options.keepDirect) result.direct = total;

        // Jacobi iteration: bounce b gathers bounce b-1 everywhere before anything overwrites it.
        if (channels == 3) previous = total;
        std::vector<float> next(options.bounces > 1 ? previous.size() : 0);
        stats.transferBytes += (previous.size() + next.size()) * sizeof(float);
        for (int b = 1; b <= options.bounces; ++b) {
            double start = nowSeconds();
            bool last = b == options.bounces;
            std::optional<Progress> progress =
                maybeProgress(options, "transfer bounce " + std::to_string(b), mesh.vertexCount());
            bounce(context, hitBlocks, channels, previous.data(), mesh.indices.data(), last ? nullptr : next.data(),
                   total.data(), b, progress ? &*progress : nullptr);
            finish(progress);
            if (!last) previous.swap(next);
            stats.bounceSeconds.push_back(nowSeconds() - start);
        }
    });
    stats.peakMemoryBytes = peakMemoryBytes();
    return result;
}

Transfer computeTransferAt(const TriMesh& geometry, const Receivers& receivers, const TransferOptions& options) {
    rays::validateMesh(geometry);
    rays::validateReceivers(receivers);
    checkOptions(geometry, options);
    const bool gather = options.mode == TransferMode::Interreflected && options.bounces > 0;

    Transfer result;
    result.order = options.order;
    result.vertexBegin = 0;
    result.vertexEnd = receivers.count;
    TransferStats& stats = result.stats;

    // Bounces 1..B reach a receiver as one gather of the geometry's (B - 1)-bounce vertex transfer, which already
    // holds the direct light and bounces 1..B-1 leaving each hit point.
    std::vector<float> outgoing;
    if (gather) {
        TransferOptions vertexOptions = options;
        vertexOptions.bounces = options.bounces - 1;
        if (vertexOptions.bounces == 0) vertexOptions.mode = TransferMode::Shadowed; // the same direct estimate
        vertexOptions.vertexBegin = 0;
        vertexOptions.vertexEnd = SIZE_MAX;
        Transfer vertex = computeTransfer(geometry, vertexOptions);
        outgoing = std::move(vertex.coefficients);
        stats.bounceSeconds.push_back(vertex.stats.directSeconds);
        for (double seconds : vertex.stats.bounceSeconds) stats.bounceSeconds.push_back(seconds);
        stats.rays += vertex.stats.rays;
    }

    Context context = makeContext(geometry, options, receivers);
    stats.rayOffset = context.offset;
    std::vector<float>& total = result.coefficients;
    total.resize(receivers.count * context.stride);
    if (gather && options.keepDirect) result.direct.resize(total.size());
    stats.transferBytes = (total.size() + result.direct.size() + outgoing.size()) * sizeof(float);

    tbb::task_arena arena(arenaConcurrency(options.threads));
    arena.execute([&] {
        if (options.mode == TransferMode::Unshadowed) {
            stats.directSeconds = unshadowedPass(context, total.data());
            return;
        }
        double start = nowSeconds();
        EmbreeScene scene(geometry, options.surface);
        stats.buildSeconds = nowSeconds() - start;
        start = nowSeconds();
        std::clock_t cpuStart = std::clock();
        DirectCounts counts;
        std::optional<Progress> progress = maybeProgress(options, "transfer at receivers", receivers.count);
        // Chunks of whole blocks: the hit records of one chunk at a time, gathered at once and dropped.
        constexpr size_t kChunk = 32 * rays::kBlockVertices;
        for (size_t first = 0; first < receivers.count; first += kChunk) {
            size_t count = std::min(kChunk, receivers.count - first);
            context.receivers = rays::receiverSlice(receivers, first, count);
            float* rows = total.data() + first * context.stride;
            std::vector<HitBlock> hitBlocks(gather ? (count + rays::kBlockVertices - 1) / rays::kBlockVertices : 0);
            directPass(context, scene, rows, nullptr, gather ? &hitBlocks : nullptr, counts,
                       progress ? &*progress : nullptr);
            if (!gather) continue;
            if (options.keepDirect)
                std::copy(rows, rows + count * context.stride, result.direct.begin() + first * context.stride);
            stats.hitRecordBytes = std::max(stats.hitRecordBytes, hitRecordBytes(hitBlocks));
            bounce(context, hitBlocks, 3, outgoing.data(), context.mesh.indices.data(), nullptr, rows, 1, nullptr);
        }
        finish(progress);
        stats.directCpuSeconds = double(std::clock() - cpuStart) / CLOCKS_PER_SEC;
        stats.directSeconds = nowSeconds() - start;
        stats.rays += counts.rays;
        stats.hits = counts.hits;
        stats.backFaceHits = counts.backFaceHits;
    });
    stats.peakMemoryBytes = peakMemoryBytes();
    return result;
}

} // namespace prt
