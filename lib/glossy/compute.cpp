// The glossy stage: per chunk of vertices, visibility over the grid (Embree), the kernel for every view above
// the horizon, a first independent fit, lobe alignment across views, then the coherence fit; the chunk's kernels
// are dropped before the next chunk, so memory is one chunk plus the output.
#include "glossy.h"
#include "glossy_internal.h"

#include "core.h"
#include "raycast.h"

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <deque>
#include <limits>
#include <optional>

namespace prt::glossy {

int heldOutResolution(const GlossyOptions& options) {
    return options.heldOutResolution > 0 ? options.heldOutResolution : std::min(64, 2 * options.gridResolution);
}

Solver parseSolver(const std::string& name) {
    if (name == "pocl" || name == "opencl") return Solver::OpenCl;
    if (name == "ceres") return Solver::Ceres;
    throw Error("", "--solver", "'" + name + "' is not pocl or ceres", kExitUsage);
}

namespace {

void checkOptions(const TriMesh& mesh, const GlossyOptions& options) {
    if (!(options.phong.exponent > 0.0 && std::isfinite(options.phong.exponent)))
        throw Error("", "--brdf", "the Phong exponent must be > 0", kExitUsage);
    if (!(options.phong.ks >= 0.0 && options.phong.ks <= 1.0))
        throw Error("", "--brdf", "KS must lie in [0, 1]", kExitUsage);
    if (options.lobes < 1 || options.lobes > kMaxLobes)
        throw Error("", "--lobes", "must lie in 1.." + std::to_string(kMaxLobes) + ", got " +
                                       std::to_string(options.lobes), kExitUsage);
    if (options.gridResolution < 2 || options.gridResolution > 64)
        throw Error("", "--grid", "cube resolution must lie in 2..64", kExitUsage);
    if (options.heldOutResolution != 0 && (options.heldOutResolution < 2 || options.heldOutResolution > 64))
        throw Error("", "--held-out-grid", "cube resolution must lie in 2..64 (0: twice --grid)", kExitUsage);
    if (options.chunkVertices < 1) throw Error("", "chunk", "must be >= 1", kExitUsage);
    if (!(options.nestedMargin >= 0.0 && options.nestedMargin < 1.0))
        throw Error("", "--nested-margin", "must lie in [0, 1)", kExitUsage);
    if (!options.nestedLighting.empty() &&
        (!options.nested || options.nestedLighting.size() % heldOutGrid(heldOutResolution(options)).count() != 0))
        throw Error("", "--nested-lighting", "needs --nested and rows of the held-out grid's size", kExitUsage);
    if (options.nestedMaxNorm && (!options.nested || !options.nestedLighting.empty()))
        throw Error("", "--nested-max", "needs --nested and not --nested-lighting", kExitUsage);
    if (options.fromBelow && (options.nested || options.warmStart))
        throw Error("", "--from-below",
                    "fits each lobe on what the earlier ones leave: not with --nested or --warm-start", kExitUsage);
    if (!(options.fromBelowOvershoot > 0.0 && options.fromBelowOvershoot <= 1e6))
        throw Error("", "--overshoot", "must lie in (0, 1e6]", kExitUsage);
    if (mesh.normals.size() != mesh.positions.size())
        throw Error("", "mesh", "has no vertex normals (prt meshprep adds them)");
    if (!options.indirectTransfer.empty() &&
        (options.indirectOrder < 1 ||
         options.indirectTransfer.size() != mesh.vertexCount() * size_t(options.indirectOrder) * options.indirectOrder))
        throw Error("", "--indirect-glossy", "the indirect transfer has not V x order^2 values", kExitFailure);
}

} // namespace

void toOutput(const float* solver, float* out, int lobes) {
    for (int k = 0; k < lobes; ++k) {
        const float* s = solver + k * kLobeParams;
        float* o = out + k * kLobeParams;
        double length = std::sqrt(double(s[1]) * s[1] + double(s[2]) * s[2] + double(s[3]) * s[3]);
        o[0] = s[0];
        for (int c = 0; c < 3; ++c) o[1 + c] = float(s[1 + c] / length);
        o[4] = float(std::exp(double(s[4])));
    }
}
void toSolver(const float* out, float* solver, int lobes) {
    for (int k = 0; k < lobes; ++k) {
        std::copy_n(out + k * kLobeParams, 4, solver + k * kLobeParams);
        solver[k * kLobeParams + 4] = float(std::log(double(out[k * kLobeParams + 4])));
    }
}

void solve(const DirectionGrid& grid, FitBatch& batch, const FitWeights& weights, const GlossyOptions& options) {
    if (batch.problems == 0) return;
    if (options.solver == Solver::OpenCl)
        solveOpenCl(grid, batch, weights, options.bounds, options.solverOptions);
    else
        solveCeres(grid, batch, weights, options.bounds, options.solverOptions);
}

namespace {

// Views of one vertex in breadth-first order over the view graph from the fitted view nearest the normal; each
// entry's parent is an earlier fitted view (or -1 for the root of a component).
std::vector<std::pair<int, int>> viewOrder(const std::vector<int>& slot, const float normal[3]) {
    const ViewSet& views = viewSet();
    std::vector<std::pair<int, int>> order;
    std::vector<char> seen(kViewCount, 0);
    for (;;) {
        int root = -1;
        double best = -2.0;
        for (int v = 0; v < kViewCount; ++v) {
            if (seen[v] || slot[v] < 0) continue;
            const auto& d = views.directions[v];
            double c = d[0] * normal[0] + d[1] * normal[1] + d[2] * normal[2];
            if (c > best) best = c, root = v;
        }
        if (root < 0) return order;
        std::deque<std::pair<int, int>> queue{{root, -1}};
        seen[root] = 1;
        while (!queue.empty()) {
            auto [v, parent] = queue.front();
            queue.pop_front();
            order.push_back({v, parent});
            for (uint32_t n : views.neighbours[v])
                if (!seen[n] && slot[n] >= 0) seen[n] = 1, queue.push_back({int(n), v});
        }
    }
}

Chunk tabulateChunk(const TriMesh& mesh, const DirectionGrid& grid, const DirectionGrid* heldOut,
                    const GlossyOptions& options, const EmbreeScene& embree, float offset,
                    const std::vector<float>& spawnNormal, size_t chunkBegin, size_t chunkEnd, tbb::task_arena& arena,
                    std::atomic<uint64_t>& rays) {
    const ViewSet& views = viewSet();
    const int lobes = options.lobes, width = lobes * kLobeParams;
    const size_t count = grid.count(), chunk = chunkEnd - chunkBegin;
    const size_t heldCount = heldOut ? heldOut->count() : 0;
    const EmbreeScene* scene = &embree;
    Chunk result;
    auto& slot = result.slot;
    auto& normals = result.normals;
    auto& first = result.first;
    auto& batch = result.batch;
    slot.assign(chunk, std::vector<int>(kViewCount, -1));
    normals.resize(chunk);
    result.visibleShare.assign(chunk, 0.0f);
    for (size_t i = 0; i < chunk; ++i) {
        const float* n = &mesh.normals[(chunkBegin + i) * 3];
        double length = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
        for (int c = 0; c < 3; ++c) normals[i][c] = float(n[c] / length);
    }
    // Kernels for every view above the horizon, visibility shared by the views of a vertex.
    std::vector<std::vector<float>> kernels(chunk), heldKernels(chunk);
    const bool indirect = !options.indirectTransfer.empty();
    const size_t coefficients = size_t(options.indirectOrder) * options.indirectOrder;
    const std::vector<float> basis = indirect ? gridBasis(grid, options.indirectOrder) : std::vector<float>();
    const std::vector<float> heldBasis =
        indirect && heldOut ? gridBasis(*heldOut, options.indirectOrder) : std::vector<float>();
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, chunk, 1), [&](const tbb::blocked_range<size_t>& r) {
            RTCIntersectContext context;
            rtcInitIntersectContext(&context);
            uint64_t cast = 0;
            // Visibility of every direction of `g` above the tangent plane and, with indirect glossy, each blocked
            // direction's hit transfer.
            auto castGrid = [&](const DirectionGrid& g, const float* p, const float* n, size_t vertex,
                                std::vector<uint8_t>& visible, std::vector<float>& hits) {
                visible.assign(g.count(), 0);
                hits.assign(indirect ? g.count() * coefficients : 0, 0.0f);
                for (size_t t = 0; t < g.count(); ++t) {
                    const float* d = &g.directions[t * 3];
                    if (n[0] * d[0] + n[1] * d[1] + n[2] * d[2] <= 0.0f) { visible[t] = 0; continue; }
                    // The shared spawn rule (lib/raycast), so glossy visibility leaks at creases no more than transfer's.
                    float origin[3];
                    spawnOrigin(p, &spawnNormal[vertex * 3], offset, origin);
                    ++cast;
                    if (!indirect) {
                        RTCRay ray;
                        spawnRay(ray, origin, d[0], d[1], d[2]);
                        rtcOccluded1(scene->scene, &context, &ray);
                        visible[t] = ray.tfar >= 0.0f;
                        continue;
                    }
                    RTCRayHit rayHit;
                    spawnRay(rayHit.ray, origin, d[0], d[1], d[2]);
                    rayHit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                    rtcIntersect1(scene->scene, &context, &rayHit);
                    visible[t] = rayHit.hit.geomID == RTC_INVALID_GEOMETRY_ID;
                    float* row = &hits[t * coefficients];
                    // Embree's Ng is (v1 - v0) x (v2 - v0): a back face (facing > 0) reflects nothing, as in transfer.
                    const RTCHit& hit = rayHit.hit;
                    if (!visible[t] && hit.Ng_x * d[0] + hit.Ng_y * d[1] + hit.Ng_z * d[2] < 0.0f)
                        hitTransfer(mesh, options.indirectTransfer, options.indirectOrder, hit.primID, hit.u, hit.v, row);
                }
            };
            std::vector<uint8_t> visible, heldVisible;
            std::vector<float> hits, heldHits;
            for (size_t i = r.begin(); i < r.end(); ++i) {
                const float* p = &mesh.positions[(chunkBegin + i) * 3];
                const float* n = normals[i].data();
                castGrid(grid, p, n, chunkBegin + i, visible, hits);
                if (heldOut) castGrid(*heldOut, p, n, chunkBegin + i, heldVisible, heldHits);
                double upper = 0.0, seen = 0.0;
                for (size_t t = 0; t < count; ++t) {
                    const float* d = &grid.directions[t * 3];
                    if (n[0] * d[0] + n[1] * d[1] + n[2] * d[2] <= 0.0f) continue;
                    upper += grid.solidAngle[t];
                    seen += visible[t] ? grid.solidAngle[t] : 0.0f;
                }
                result.visibleShare[i] = upper > 0.0 ? float(seen / upper) : 0.0f;
                std::vector<float> table(count), heldTable(heldCount);
                for (int v = 0; v < kViewCount; ++v) {
                    const float* view = views.directions[v].data();
                    if (n[0] * view[0] + n[1] * view[1] + n[2] * view[2] <= 0.0f) continue;
                    tabulateKernel(grid, n, view, options.phong, visible.data(), table.data());
                    if (indirect)
                        addIndirectKernel(grid, basis.data(), options.indirectOrder, n, view, options.phong,
                                          visible.data(), hits.data(), table.data());
                    if (*std::max_element(table.begin(), table.end()) <= 0.0f) continue;
                    slot[i][v] = int(kernels[i].size() / count);
                    kernels[i].insert(kernels[i].end(), table.begin(), table.end());
                    if (!heldOut) continue;
                    tabulateKernel(*heldOut, n, view, options.phong, heldVisible.data(), heldTable.data());
                    if (indirect)
                        addIndirectKernel(*heldOut, heldBasis.data(), options.indirectOrder, n, view, options.phong,
                                          heldVisible.data(), heldHits.data(), heldTable.data());
                    heldKernels[i].insert(heldKernels[i].end(), heldTable.begin(), heldTable.end());
                }
            }
            rays += cast;
        });
    });
    for (auto& k : heldKernels)
        result.heldKernel.insert(result.heldKernel.end(), k.begin(), k.end()), std::vector<float>().swap(k);
    // One batch in (vertex, view) order.
    batch.lobes = lobes;
    first.assign(chunk + 1, 0);
    for (size_t i = 0; i < chunk; ++i) first[i + 1] = first[i] + kernels[i].size() / count;
    batch.problems = first[chunk];
    batch.kernel.reserve(batch.problems * count);
    for (auto& k : kernels) batch.kernel.insert(batch.kernel.end(), k.begin(), k.end()), std::vector<float>().swap(k);
    batch.params.resize(batch.problems * width);
    batch.amplitudeMax.resize(batch.problems);
    for (size_t p = 0; p < batch.problems; ++p) {
        const float* k = &batch.kernel[p * count];
        batch.amplitudeMax[p] = 4.0f * *std::max_element(k, k + count);
        initialise(grid, k, lobes, options.phong.exponent, options.bounds, &batch.params[p * width]);
    }
    return result;
}

} // namespace

std::vector<float> coherencePass(const DirectionGrid& grid, Chunk& tabulated, const GlossyOptions& options,
                                 bool coherence) {
    const ViewSet& views = viewSet();
    FitBatch& batch = tabulated.batch;
    const auto& slot = tabulated.slot;
    const auto& first = tabulated.first;
    const auto& normals = tabulated.normals;
    const size_t chunk = slot.size();
    const int lobes = batch.lobes, width = lobes * kLobeParams;
    std::vector<float> fitted(batch.problems * width);
    for (size_t p = 0; p < batch.problems; ++p) toOutput(&batch.params[p * width], &fitted[p * width], lobes);
    if (coherence) {
        // Align lobe order across each vertex's views, then refit with priors from the aligned neighbours.
        batch.prior.assign(batch.problems * lobes * 4, 0.0f);
        batch.hasPrior.assign(batch.problems, 0);
        for (size_t i = 0; i < chunk; ++i) {
            auto problem = [&](int v) { return first[i] + size_t(slot[i][v]); };
            for (auto [v, parent] : viewOrder(slot[i], normals[i].data()))
                if (parent >= 0 && lobes > 1)
                    alignLobes(&fitted[problem(parent) * width], &fitted[problem(v) * width], lobes);
            for (int v = 0; v < kViewCount; ++v) {
                if (slot[i][v] < 0) continue;
                size_t p = problem(v);
                double sum[kMaxLobes][4] = {};
                int neighbours = 0;
                for (uint32_t n : views.neighbours[v]) {
                    if (slot[i][n] < 0) continue;
                    const float* q = &fitted[problem(int(n)) * width];
                    ++neighbours;
                    for (int k = 0; k < lobes; ++k) {
                        for (int c = 0; c < 3; ++c) sum[k][c] += q[k * kLobeParams + 1 + c];
                        sum[k][3] += std::log(double(q[k * kLobeParams + 4]));
                    }
                }
                if (neighbours == 0) continue;
                batch.hasPrior[p] = 1;
                for (int k = 0; k < lobes; ++k) {
                    double length = std::sqrt(sum[k][0] * sum[k][0] + sum[k][1] * sum[k][1] + sum[k][2] * sum[k][2]);
                    float* prior = &batch.prior[(p * lobes + k) * 4];
                    for (int c = 0; c < 3; ++c)
                        prior[c] = length > 0 ? float(sum[k][c] / length) : fitted[p * width + k * kLobeParams + 1 + c];
                    prior[3] = float(sum[k][3] / neighbours);
                }
            }
        }
        for (size_t p = 0; p < batch.problems; ++p) toSolver(&fitted[p * width], &batch.params[p * width], lobes);
        solve(grid, batch, options.weights, options);
        for (size_t p = 0; p < batch.problems; ++p) toOutput(&batch.params[p * width], &fitted[p * width], lobes);
    }
    return fitted;
}

GlossyLobes computeGlossyLobes(const TriMesh& mesh, const GlossyOptions& options) {
    checkOptions(mesh, options);
    const ViewSet& views = viewSet();
    const DirectionGrid grid = cubeGrid(options.gridResolution);
    const int lobes = options.lobes, width = lobes * kLobeParams;
    const size_t count = grid.count();
    GlossyLobes result;
    result.lobes = lobes;
    result.vertexBegin = std::min(options.vertexBegin, mesh.vertexCount());
    result.vertexEnd = std::clamp(options.vertexEnd, result.vertexBegin, mesh.vertexCount());
    const size_t vertices = result.vertexEnd - result.vertexBegin;
    result.values.assign(vertices * kViewCount * width, 0.0f);
    result.vertexStats.assign(vertices * kVertexStatColumns, 0.0f);
    const bool coherence = options.weights.beta > 0 || options.weights.gamma > 0 || options.weights.delta > 0;
    const DirectionGrid heldGrid = options.nested ? heldOutGrid(heldOutResolution(options)) : DirectionGrid();
    if (options.nested) result.heldOutError.assign(vertices * kViewCount, -1.0f), result.keptStage.assign(size_t(lobes), 0);

    tbb::task_arena arena(arenaConcurrency(options.solverOptions.threads));
    std::optional<EmbreeScene> scene;
    arena.execute([&] { scene.emplace(mesh); });
    const float offset = rayOffset(mesh);
    const std::vector<float> spawn = spawnNormals(mesh);
    std::atomic<uint64_t> rays{0};
    double costSum = 0.0, errorSum = 0.0;
    std::optional<Progress> progress;
    if (options.progress) progress.emplace("glossy", vertices);

    for (size_t chunkBegin = result.vertexBegin; chunkBegin < result.vertexEnd; chunkBegin += options.chunkVertices) {
        const size_t chunkEnd = std::min(result.vertexEnd, chunkBegin + options.chunkVertices);
        const size_t chunk = chunkEnd - chunkBegin;
        double tabulateStart = nowSeconds();
        Chunk tabulated = tabulateChunk(mesh, grid, options.nested ? &heldGrid : nullptr, options, *scene, offset, spawn, chunkBegin, chunkEnd, arena, rays);
        auto& slot = tabulated.slot;
        auto& normals = tabulated.normals;
        auto& first = tabulated.first;
        FitBatch& batch = tabulated.batch;
        result.stats.tabulateSeconds += nowSeconds() - tabulateStart;

        double fitStart = nowSeconds();
        std::vector<float> fitted;
        if (options.nested) {
            std::vector<double> heldCost;
            fitted = nestedFit(grid, heldGrid, tabulated, options, coherence, heldCost, result.keptStage);
            for (size_t i = 0; i < chunk; ++i)
                for (int v = 0; v < kViewCount; ++v) {
                    if (slot[i][v] < 0) continue;
                    size_t p = first[i] + size_t(slot[i][v]);
                    double energy = dataEnergy(heldGrid, &tabulated.heldKernel[p * heldGrid.count()]);
                    result.heldOutError[(chunkBegin - result.vertexBegin + i) * kViewCount + size_t(v)] =
                        float(energy > 0 ? heldCost[p] / energy : 0.0);
                }
        } else if (options.fromBelow) {
            fitted = fromBelowFit(grid, tabulated, options, coherence);
        } else {
            if (options.warmStart && lobes > 1)
                warmStartFit(grid, batch, options);
            else
                solve(grid, batch, FitWeights{}, options);
            fitted = coherencePass(grid, tabulated, options, coherence);
        }
        result.stats.fitSeconds += nowSeconds() - fitStart;
        for (size_t i = 0; i < chunk; ++i) {
            float* stat = &result.vertexStats[(chunkBegin - result.vertexBegin + i) * kVertexStatColumns];
            std::copy_n(normals[i].data(), 3, stat);
            stat[3] = tabulated.visibleShare[i];
            double mean = 0, worst = 0;
            for (size_t p = first[i]; p < first[i + 1]; ++p) {
                double energy = dataEnergy(grid, &batch.kernel[p * count]);
                double error = energy > 0 ? std::sqrt(batch.cost[p] / energy) : 0.0;
                costSum += batch.cost[p];
                errorSum += error;
                mean += error;
                worst = std::max(worst, error);
            }
            stat[4] = first[i + 1] > first[i] ? float(mean / double(first[i + 1] - first[i])) : 0.0f;
            stat[5] = float(worst);
        }
        result.stats.problems += batch.problems;

        // Output rows; views without a fit get a = 0, the mirror direction and the exponent.
        for (size_t i = 0; i < chunk; ++i) {
            const float* n = normals[i].data();
            for (int v = 0; v < kViewCount; ++v) {
                float* out = &result.values[((chunkBegin - result.vertexBegin + i) * kViewCount + v) * width];
                if (slot[i][v] >= 0) {
                    std::copy_n(&fitted[(first[i] + size_t(slot[i][v])) * width], width, out);
                    continue;
                }
                const float* view = views.directions[v].data();
                float c = n[0] * view[0] + n[1] * view[1] + n[2] * view[2];
                for (int k = 0; k < lobes; ++k) {
                    float* o = out + k * kLobeParams;
                    o[0] = 0.0f;
                    for (int a = 0; a < 3; ++a) o[1 + a] = 2.0f * c * n[a] - view[a];
                    o[4] = float(options.phong.exponent);
                }
            }
        }
        if (progress) progress->add(chunk);
    }
    if (progress) progress->finish();
    countFlips(mesh, result);
    result.stats.rays = rays;
    result.stats.meanCost = result.stats.problems ? costSum / double(result.stats.problems) : 0.0;
    result.stats.meanRelativeError = result.stats.problems ? errorSum / double(result.stats.problems) : 0.0;
    result.stats.peakMemoryBytes = peakMemoryBytes();
    return result;
}

FitBatch stageProblems(const TriMesh& mesh, const GlossyOptions& options, size_t problems, uint64_t& rayCount) {
    checkOptions(mesh, options);
    const DirectionGrid grid = cubeGrid(options.gridResolution);
    const int width = options.lobes * kLobeParams;
    tbb::task_arena arena(arenaConcurrency(options.solverOptions.threads));
    std::optional<EmbreeScene> scene;
    arena.execute([&] { scene.emplace(mesh); });
    const std::vector<float> spawn = spawnNormals(mesh);
    std::atomic<uint64_t> rays{0};
    FitBatch all;
    all.lobes = options.lobes;
    for (size_t begin = 0; begin < mesh.vertexCount() && all.problems < problems; begin += options.chunkVertices) {
        size_t end = std::min(mesh.vertexCount(), begin + options.chunkVertices);
        Chunk chunk = tabulateChunk(mesh, grid, nullptr, options, *scene, rayOffset(mesh), spawn, begin, end, arena, rays);
        size_t take = std::min(chunk.batch.problems, problems - all.problems);
        all.kernel.insert(all.kernel.end(), chunk.batch.kernel.begin(), chunk.batch.kernel.begin() + take * grid.count());
        all.params.insert(all.params.end(), chunk.batch.params.begin(), chunk.batch.params.begin() + take * width);
        all.amplitudeMax.insert(all.amplitudeMax.end(), chunk.batch.amplitudeMax.begin(),
                                chunk.batch.amplitudeMax.begin() + take);
        all.problems += take;
    }
    rayCount = rays.load();
    return all;
}

} // namespace prt::glossy
