// The passes of a sharded interreflected transfer (transfer.h): each job does for its vertex rows what
// computeTransfer does for all of them, through the same functions (passes.h), so the rows agree bit for bit.
#include "passes.h"

#include <tbb/task_arena.h>

#include <optional>

namespace prt {

using namespace passes;

namespace {

// The mesh must be the one the run was made from (its counts; the hash is the caller's, from the file).
void checkMesh(const TriMesh& mesh, const ShardRun& run) {
    rays::validateMesh(mesh);
    checkOptions(mesh, run.options);
    if (mesh.vertexCount() != run.vertexCount || mesh.triangleCount() != run.triangleCount ||
        bounceChannels(mesh, run.options) != run.channels || run.rowEnd > run.vertexCount || run.rowBegin > run.rowEnd)
        throw Error("", "shard", "the mesh is not the one this shard run was made for", kExitUsage);
}

// computeTransfer's options for the shard's rows.
TransferOptions rangeOptions(const ShardRun& run) {
    TransferOptions options = run.options;
    options.vertexBegin = run.rowBegin;
    options.vertexEnd = run.rowEnd;
    return options;
}

// The vertices a bounce over `hitBlocks` gathers from, the corners of its hit triangles: 1 in needed[v] for those.
// Needs triangles below mesh.triangleCount() (readHitRecords checks them).
std::vector<uint8_t> hitCorners(const TriMesh& mesh, const std::vector<HitBlock>& hitBlocks) {
    std::vector<uint8_t> needed(mesh.vertexCount(), 0);
    for (const HitBlock& block : hitBlocks)
        for (uint32_t t : block.triangle)
            for (int k = 0; k < 3; ++k) needed[mesh.indices[3 * size_t(t) + k]] = 1;
    return needed;
}

// bounce()'s table for rows packed in vertex order from those `needed` marks (readExitant): each triangle corner's
// row among them, 0 for a corner no hit reads.
std::vector<uint32_t> packedCornerRows(const TriMesh& mesh, const std::vector<uint8_t>& needed) {
    std::vector<uint32_t> rowOf(needed.size(), 0);
    uint32_t rows = 0;
    for (size_t v = 0; v < needed.size(); ++v)
        if (needed[v]) rowOf[v] = rows++;
    std::vector<uint32_t> cornerRows(mesh.indices.size());
    for (size_t i = 0; i < cornerRows.size(); ++i) cornerRows[i] = rowOf[mesh.indices[i]];
    return cornerRows;
}

} // namespace

ShardRun makeShardRun(const TriMesh& mesh, const TransferOptions& options, const std::string& meshHash,
                      int shardIndex, int shardCount) {
    if (options.mode != TransferMode::Interreflected || options.bounces < 1)
        throw Error("", "shard", "the sharded passes are for interreflected transfer with bounces", kExitUsage);
    if (shardCount < 1 || shardIndex < 0 || shardIndex >= shardCount)
        throw Error("", "--shard", std::to_string(shardIndex) + "/" + std::to_string(shardCount) + " is not a shard",
                    kExitUsage);
    ShardRun run;
    run.meshHash = meshHash;
    run.vertexCount = mesh.vertexCount();
    run.triangleCount = mesh.triangleCount();
    run.options = options;
    run.channels = bounceChannels(mesh, options);
    run.shardIndex = shardIndex;
    run.shardCount = shardCount;
    RowRange range = shardRows(run.vertexCount, shardIndex, shardCount);
    run.rowBegin = range.begin;
    run.rowEnd = range.end;
    return run;
}

ShardRows computeDirectShard(const TriMesh& mesh, const ShardRun& run, const std::string& hitsPath,
                             TransferStats& stats) {
    checkMesh(mesh, run);
    const TransferOptions options = rangeOptions(run);
    const std::vector<float> spawn = spawnNormals(mesh, run.rowBegin, run.rowEnd); // its receivers' only
    Context context =
        makeContext(mesh, options, rays::vertexReceivers(mesh, options, run.rowBegin, run.rowEnd, spawn.data()));
    const size_t rows = run.rowEnd - run.rowBegin;

    ShardRows result;
    result.rowBegin = run.rowBegin;
    result.rowEnd = run.rowEnd;
    result.total.resize(rows * context.stride);
    if (run.channels == 1) result.exitant.resize(rows * context.coefficients);
    std::vector<HitBlock> hitBlocks(hitBlockCount(rows));
    tbb::task_arena arena(arenaConcurrency(options.threads));
    arena.execute([&] {
        runDirectPass(context, result.total.data(), run.channels == 1 ? result.exitant.data() : nullptr, &hitBlocks,
                      stats);
    });
    // As computeTransfer: the direct rows are kept (keepDirect), and RGB bounces start from them.
    result.direct = result.total;
    if (run.channels == 3) result.exitant = result.total;
    result.rays = stats.rays;
    result.hits = stats.hits;
    result.backFaceHits = stats.backFaceHits;
    result.rayOffset = stats.rayOffset = context.offset;
    stats.transferBytes = (result.total.size() + result.direct.size() + result.exitant.size()) * sizeof(float);
    writeHitRecords(hitsPath, run, hitBlocks);
    stats.peakMemoryBytes = peakMemoryBytes();
    return result;
}

ShardRows computeBounceShard(const TriMesh& mesh, const ShardRun& run, int pass, const std::string& previousPath,
                             const std::string& hitsPath, const std::string& exitantPath, TransferStats& stats) {
    checkMesh(mesh, run);
    if (pass < 1 || pass > run.options.bounces)
        throw Error("", "--pass", std::to_string(pass) + " outside 1.." + std::to_string(run.options.bounces),
                    kExitUsage);
    ShardRows rows = readShardRows(previousPath, run, pass - 1);
    const std::vector<HitBlock> hitBlocks = readHitRecords(hitsPath, run);
    // Only the rows its hits gather from: around the shard's own part of a large scene, a fraction of the array.
    const std::vector<uint8_t> needed = hitCorners(mesh, hitBlocks);
    const std::vector<float> previous = readExitant(exitantPath, run, pass - 1, needed);
    const std::vector<uint32_t> cornerRows = packedCornerRows(mesh, needed);

    const TransferOptions options = rangeOptions(run);
    // No ray is cast, so no spawn normals (their sort by position was a fifth of a bounce job at 10 M triangles).
    Context context =
        makeContext(mesh, options, rays::vertexReceivers(mesh, options, run.rowBegin, run.rowEnd, nullptr));
    const bool last = pass == run.options.bounces;
    std::vector<float> next(last ? 0 : (run.rowEnd - run.rowBegin) * context.coefficients * run.channels);
    stats.rayOffset = context.offset;
    stats.hits = rows.hits;
    stats.hitRecordBytes = hitRecordBytes(hitBlocks);
    stats.exitantRows = previous.size() / (size_t(context.coefficients) * run.channels);
    stats.transferBytes = (rows.total.size() + rows.direct.size() + previous.size() + next.size()) * sizeof(float) +
                          cornerRows.size() * sizeof(uint32_t);
    double start = nowSeconds();
    tbb::task_arena arena(arenaConcurrency(options.threads));
    arena.execute([&] {
        std::optional<Progress> progress;
        if (options.progress) progress.emplace("transfer bounce " + std::to_string(pass), run.rowEnd - run.rowBegin);
        bounce(context, hitBlocks, run.channels, previous.data(), cornerRows.data(), last ? nullptr : next.data(),
               rows.total.data(), pass, progress ? &*progress : nullptr);
        if (progress) progress->finish();
    });
    stats.bounceSeconds.push_back(nowSeconds() - start);
    rows.pass = pass;
    rows.exitant = std::move(next);
    stats.peakMemoryBytes = peakMemoryBytes();
    return rows;
}

} // namespace prt
