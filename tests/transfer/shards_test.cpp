// Sharded interreflected transfer through the prt binary: the passes (direct shards with their hit records, a
// gather and a sharded job per bounce, `prt merge` at the end) give the unsharded bundle byte for byte, also with
// more shards than vertices; a hit-record, rows or exitant file of another run, shard or pass is refused (exit 3,
// the file and the problem named) and no output is left.
#include "bundle.h"
#include "core.h"
#include "scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace prt {
namespace {

const std::string kPrt = PRT_BINARY_DIR "/prt";

struct CliRun {
    int exitCode;
    std::string stderrText;
};

class TransferShards : public ::testing::Test {
protected:
    fs::path dir;

    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir = fs::temp_directory_path() / ("prt_transfer_shards_" + std::to_string(getpid()) + "_" + info->name());
        fs::remove_all(dir);
        fs::create_directories(dir);
    }
    void TearDown() override { fs::remove_all(dir); }

    std::string path(const std::string& name) const { return (dir / name).string(); }

    CliRun run(const std::string& arguments) const {
        std::string log = path("stderr.txt");
        int status = std::system((kPrt + " --quiet " + arguments + " 2> " + log).c_str());
        std::stringstream text;
        text << std::ifstream(log).rdbuf();
        return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, text.str()};
    }
    void ok(const std::string& arguments) const {
        CliRun result = run(arguments);
        ASSERT_EQ(result.exitCode, 0) << arguments << "\n" << result.stderrText;
    }

    std::string writeMesh(const std::string& name, const TriMesh& mesh) const {
        Bundle bundle;
        bundle.mesh = mesh;
        writeBundle(path(name), bundle);
        return path(name);
    }

    // `prt transfer MESH OPTIONS` through every pass in `shards` shards, merged into NAME.glb; returns its path.
    std::string sharded(const std::string& mesh, const std::string& options, int shards, int bounces,
                        const std::string& name) const {
        std::string transfer = "transfer " + mesh + " " + options + " --bounces " + std::to_string(bounces);
        auto shard = [&](int i) { return " --shard " + std::to_string(i) + "/" + std::to_string(shards); };
        auto rows = [&](int pass, int i) { return path(name + ".p" + std::to_string(pass) + "." + std::to_string(i)); };
        auto exitant = [&](int pass) { return path(name + ".e" + std::to_string(pass)); };
        for (int i = 0; i < shards; ++i) ok(transfer + shard(i) + " -o " + rows(0, i));
        std::string bundles;
        for (int pass = 1; pass <= bounces; ++pass) {
            std::string parts;
            for (int i = shards - 1; i >= 0; --i) parts.append(" ").append(rows(pass - 1, i)); // any order
            ok(transfer + " --gather" + parts + " -o " + exitant(pass - 1));
            for (int i = 0; i < shards; ++i) {
                std::string out = pass == bounces ? rows(pass, i) + ".glb" : rows(pass, i);
                ok(transfer + shard(i) + " --pass " + std::to_string(pass) + " --previous " + rows(pass - 1, i) +
                   " --hits " + rows(0, i) + ".hits --exitant " + exitant(pass - 1) + " -o " + out);
                if (pass == bounces) bundles += " " + out;
            }
        }
        ok("merge" + bundles + " -o " + path(name + ".glb"));
        return path(name + ".glb");
    }
};

TEST_F(TransferShards, ThreeShardsTwoBouncesMergeIntoTheUnshardedBundle) {
    std::string mesh = writeMesh("spheres.glb", makeTwoSpheres(8, 16)); // they light each other
    std::string options = "--mode interreflected --order 3 --samples 48";
    ok("transfer " + mesh + " " + options + " --bounces 2 -o " + path("whole.glb"));
    std::string merged = sharded(mesh, options, 3, 2, "sharded");
    EXPECT_EQ(readFileBytes(merged), readFileBytes(path("whole.glb")));
    // The unsharded bundle's bounce layer comes through the merge too.
    Bundle bundle = readBundle(merged);
    ASSERT_EQ(bundle.layers.size(), 2u);
    EXPECT_EQ(bundle.layers[1].name, "transfer_bounce");
    EXPECT_EQ(bundle.layers[1].domain, "vertex");
}

TEST_F(TransferShards, PerVertexAlbedoBouncesInRgbAlsoMatch) {
    std::string mesh = writeMesh("room.glb", makeScene("box-room")); // coloured walls: per-vertex albedo
    std::string options = "--mode interreflected --order 2 --samples 32";
    ok("transfer " + mesh + " " + options + " --bounces 3 -o " + path("whole.glb"));
    EXPECT_EQ(readFileBytes(sharded(mesh, options, 4, 3, "sharded")), readFileBytes(path("whole.glb")));
}

// Two closed rooms far apart: no ray leaves either, so a bounce shard of the first room's vertices gathers from
// none of the second's, and reads only its own rows of the exitant array (what its log reports), with the bundle
// still the unsharded one byte for byte.
TEST_F(TransferShards, ABounceShardReadsOnlyTheExitantRowsItsHitsName) {
    TriMesh near = makeScene("box-room"), far = near; // coloured walls: RGB bounces
    for (size_t i = 0; i < far.positions.size(); i += 3) far.positions[i] += 100.0f;
    const TriMesh both = mergeMeshes({near, far});
    const size_t roomVertices = near.vertexCount();
    ASSERT_EQ(shardRows(both.vertexCount(), 0, 2).end, roomVertices); // shard 0 is the first room
    std::string mesh = writeMesh("two_rooms.glb", both);
    std::string options = "--mode interreflected --order 2 --samples 16";
    ok("transfer " + mesh + " " + options + " --bounces 2 -o " + path("whole.glb"));
    EXPECT_EQ(readFileBytes(sharded(mesh, options, 2, 2, "rooms")), readFileBytes(path("whole.glb")));

    // Pass 1 of shard 0 again, from the files sharded() left, with its statistics.
    CliRun pass = run("transfer " + mesh + " " + options + " --bounces 2 --shard 0/2 --pass 1 --previous " +
                      path("rooms.p0.0") + " --hits " + path("rooms.p0.0.hits") + " --exitant " + path("rooms.e0") +
                      " -o " + path("again") + " --log-json");
    ASSERT_EQ(pass.exitCode, 0) << pass.stderrText;
    size_t at = pass.stderrText.find("\"exitant_rows\":");
    ASSERT_NE(at, std::string::npos) << pass.stderrText;
    const uint64_t rowsRead = std::stoull(pass.stderrText.substr(at + 15));
    EXPECT_GT(rowsRead, roomVertices / 2); // the room's own walls
    EXPECT_LE(rowsRead, roomVertices);     // none of the other room's
    EXPECT_EQ(readFileBytes(path("again")), readFileBytes(path("rooms.p1.0")));
}

// A tetrahedron seen from inside: 4 vertices whose every ray hits another face, so the bounces carry light.
TriMesh insideTetrahedron() {
    TriMesh mesh;
    mesh.positions = {1, 1, 1, 1, -1, -1, -1, 1, -1, -1, -1, 1};
    mesh.indices = {0, 1, 2, 0, 1, 3, 0, 2, 3, 1, 2, 3};
    for (size_t t = 0; t < 4; ++t) { // wind each face so that its normal points at the centre
        uint32_t* f = &mesh.indices[3 * t];
        const float *a = &mesh.positions[3 * f[0]], *b = &mesh.positions[3 * f[1]], *c = &mesh.positions[3 * f[2]];
        float u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        float n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
        if (n[0] * a[0] + n[1] * a[1] + n[2] * a[2] > 0) std::swap(f[1], f[2]);
    }
    for (size_t i = 0; i < 12; ++i) mesh.normals.push_back(-mesh.positions[i] / std::sqrt(3.0f));
    return mesh;
}

TEST_F(TransferShards, MoreShardsThanVerticesLeavesEmptyShardsThatStillMerge) {
    TriMesh room = insideTetrahedron();
    std::string mesh = writeMesh("tiny.glb", room);
    std::string options = "--mode interreflected --order 2 --samples 16";
    ok("transfer " + mesh + " " + options + " --bounces 2 -o " + path("whole.glb"));
    int shards = int(room.vertexCount()) + 3; // 7 shards of 4 vertices: three of them empty
    EXPECT_EQ(readFileBytes(sharded(mesh, options, shards, 2, "many")), readFileBytes(path("whole.glb")));
}

class TransferShardFiles : public TransferShards {
protected:
    std::string mesh, transfer;
    void SetUp() override {
        TransferShards::SetUp();
        mesh = writeMesh("spheres.glb", makeTwoSpheres(6, 12));
        transfer = "transfer " + mesh + " --mode interreflected --order 2 --samples 32 --bounces 2";
        for (int i = 0; i < 2; ++i) ok(transfer + " --shard " + std::to_string(i) + "/2 -o " + rows(i));
        ok(transfer + " --gather " + rows(0) + " " + rows(1) + " -o " + path("e0"));
    }
    std::string rows(int i) const { return path("p0." + std::to_string(i)); }

    static size_t headerLength(const std::string& file) {
        uint32_t bytes;
        std::memcpy(&bytes, file.data() + 12, 4);
        return bytes;
    }
    // Rewrites the header's checksum of `section` (`length` bytes at `offset`, under 1 MiB: one chunk) to match.
    static void reseal(std::string& file, const std::string& section, size_t offset, size_t length) {
        size_t headerBytes = headerLength(file);
        nlohmann::json head = nlohmann::json::parse(file.substr(16, headerBytes));
        ASSERT_LT(length, size_t(1) << 20);
        std::string digest = hashBytes(file.data() + offset, length);
        head["checksums"][section] = hashBytes(digest.data(), digest.size());
        std::string text = head.dump();
        ASSERT_EQ(text.size(), headerBytes);
        file.replace(16, headerBytes, text);
    }
    // `file` with one bit of byte `offsetFromEnd` (counted back from the end) flipped.
    static std::string flipped(const std::string& file, size_t offsetFromEnd) {
        std::string copy = file;
        copy[copy.size() - offsetFromEnd] ^= 0x01;
        return copy;
    }

    // Bounce 1 of shard 0 with these files must fail with exit 3, naming `file` and `problem`, writing nothing.
    void expectRefused(const std::string& previous, const std::string& hits, const std::string& exitant,
                       const std::string& file, const std::string& problem, const std::string& extra = "") {
        std::string out = path("refused.out");
        CliRun result = run(transfer + extra + " --shard 0/2 --pass 1 --previous " + previous + " --hits " + hits +
                            " --exitant " + exitant + " -o " + out);
        EXPECT_EQ(result.exitCode, 3) << result.stderrText;
        EXPECT_NE(result.stderrText.find(file), std::string::npos) << result.stderrText;
        EXPECT_NE(result.stderrText.find(problem), std::string::npos) << result.stderrText;
        EXPECT_FALSE(fs::exists(out));
    }
};

TEST_F(TransferShardFiles, GoodFilesPass) {
    ok(transfer + " --shard 0/2 --pass 1 --previous " + rows(0) + " --hits " + rows(0) + ".hits --exitant " +
       path("e0") + " -o " + path("p1.0"));
}

TEST_F(TransferShardFiles, HitRecordsOfAnotherShardOrRunAreRefused) {
    expectRefused(rows(0), rows(1) + ".hits", path("e0"), rows(1) + ".hits", "belongs to shard [1,2]");

    // Another seed: every file names the run it came from.
    std::string other = path("seed.0");
    ok(transfer + " --seed 5 --shard 0/2 -o " + other);
    expectRefused(rows(0), other + ".hits", path("e0"), other + ".hits", "was written for seed 5, this run has 0");

    // Another mesh with the same vertex count.
    TriMesh moved = makeTwoSpheres(6, 12);
    for (float& x : moved.positions) x *= 2.0f;
    std::string movedMesh = writeMesh("moved.glb", moved);
    std::string movedRows = path("moved.0");
    ok("transfer " + movedMesh + " --mode interreflected --order 2 --samples 32 --bounces 2 --shard 0/2 -o " +
       movedRows);
    expectRefused(rows(0), movedRows + ".hits", path("e0"), movedRows + ".hits", "was written for another mesh");
}

TEST_F(TransferShardFiles, TruncatedPaddedOrForeignFilesAreRefused) {
    std::string hits = readFileBytes(rows(0) + ".hits");
    writeBytesAtomic(path("short.hits"), hits.substr(0, hits.size() - 7));
    expectRefused(rows(0), path("short.hits"), path("e0"), path("short.hits"), "truncated or padded");
    writeBytesAtomic(path("long.hits"), hits + "x");
    expectRefused(rows(0), path("long.hits"), path("e0"), path("long.hits"), "truncated or padded");
    // A corrupt triangle index: the payload keeps its length, the section's checksum catches it; resealed with a
    // matching checksum (what a buggy writer would leave), the index check catches it.
    // Layout (lib/transfer/shard_files.cpp): 16-byte prefix, the header, a uint32 count per row, then triangles.
    std::string corrupt = hits;
    size_t rowsCount = shardRows(readBundle(mesh).mesh.vertexCount(), 0, 2).end;
    size_t triangles = 16 + headerLength(corrupt) + rowsCount * 4;
    uint32_t bad = 0xFFFFFFF0u;
    std::memcpy(corrupt.data() + triangles, &bad, 4);
    writeBytesAtomic(path("corrupt.hits"), corrupt);
    expectRefused(rows(0), path("corrupt.hits"), path("e0"), path("corrupt.hits"), "triangles: does not match its checksum");
    nlohmann::json head = nlohmann::json::parse(corrupt.substr(16, headerLength(corrupt)));
    size_t hitCount = head["hit_count"];
    reseal(corrupt, "triangles", triangles, hitCount * 4);
    writeBytesAtomic(path("resealed.hits"), corrupt);
    expectRefused(rows(0), path("resealed.hits"), path("e0"), path("resealed.hits"), "is not in the mesh");

    expectRefused(rows(0), rows(0) + ".hits", rows(0), rows(0), "not an exitant array");
    expectRefused(rows(0), rows(0) + ".hits", mesh, mesh, "is not a prt shard file");
    expectRefused(path("e0"), rows(0) + ".hits", path("e0"), path("e0"), "not shard rows");
}

// One flipped bit in the payload of each kind of file (a float's lowest mantissa bit: still a finite value that
// every other check accepts) is refused by name, with exit 3, and nothing is written.
TEST_F(TransferShardFiles, AFlippedPayloadByteIsRefusedByItsChecksum) {
    // The exitant array's last float, before its table of chunk digests (one chunk here), and a digest's last byte.
    const size_t table = hashBytes("", 0).size();
    writeBytesAtomic(path("e0.flipped"), flipped(readFileBytes(path("e0")), table + 4));
    expectRefused(rows(0), rows(0) + ".hits", path("e0.flipped"), path("e0.flipped"),
                  "exitant: chunk 0 does not match its checksum");
    writeBytesAtomic(path("e0.table"), flipped(readFileBytes(path("e0")), 1));
    expectRefused(rows(0), rows(0) + ".hits", path("e0.table"), path("e0.table"),
                  "digests: do not match the exitant section's checksum");
    // The previous pass's rows: the last float of their direct section, before the exitant section (order 2, one
    // channel: 4 floats per row), which a bounce skips (it gathers from the joined array; the gather checks it).
    const size_t exitantBytes = shardRows(readBundle(mesh).mesh.vertexCount(), 0, 2).end * 4 * 4;
    writeBytesAtomic(path("p0.flipped"), flipped(readFileBytes(rows(0)), exitantBytes + 4));
    expectRefused(path("p0.flipped"), rows(0) + ".hits", path("e0"), path("p0.flipped"),
                  "direct: does not match its checksum");
    // Hit records: the last sample index's low byte.
    writeBytesAtomic(path("hits.flipped"), flipped(readFileBytes(rows(0) + ".hits"), 2));
    expectRefused(rows(0), path("hits.flipped"), path("e0"), path("hits.flipped"), "samples: does not match its checksum");
    // The gather reads only the exitant rows, and checks them.
    writeBytesAtomic(path("p0.1.flipped"), flipped(readFileBytes(rows(1)), 4));
    CliRun gather = run(transfer + " --gather " + rows(0) + " " + path("p0.1.flipped") + " -o " + path("bad"));
    EXPECT_EQ(gather.exitCode, 3) << gather.stderrText;
    EXPECT_NE(gather.stderrText.find(path("p0.1.flipped")), std::string::npos) << gather.stderrText;
    EXPECT_NE(gather.stderrText.find("does not match its checksum"), std::string::npos) << gather.stderrText;
    EXPECT_FALSE(fs::exists(path("bad")));
}

TEST_F(TransferShardFiles, GatherNeedsEveryShardOfOnePassOnce) {
    CliRun twice = run(transfer + " --gather " + rows(0) + " " + rows(0) + " -o " + path("bad"));
    EXPECT_EQ(twice.exitCode, 3);
    EXPECT_NE(twice.stderrText.find("is shard 0 again"), std::string::npos) << twice.stderrText;
    CliRun missing = run(transfer + " --gather " + rows(0) + " -o " + path("bad"));
    EXPECT_EQ(missing.exitCode, 3);
    EXPECT_NE(missing.stderrText.find("is not one of 1 shards"), std::string::npos) << missing.stderrText;
    EXPECT_FALSE(fs::exists(path("bad")));
}

TEST_F(TransferShardFiles, PassFlagsOutsideShardedBouncesAreUsageErrors) {
    EXPECT_EQ(run(transfer + " --pass 1 -o " + path("x")).exitCode, 2);
    EXPECT_EQ(run(transfer + " --shard 0/2 --pass 1 -o " + path("x")).exitCode, 2); // no --previous ...
    EXPECT_EQ(run(transfer + " --shard 0/2 --pass 3 -o " + path("x")).exitCode, 2);
    EXPECT_EQ(run("transfer " + mesh + " --mode shadowed --shard 0/2 --pass 0 -o " + path("x")).exitCode, 2);
}

} // namespace
} // namespace prt
