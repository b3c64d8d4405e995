// The exitant array between sharded passes, read the way a bounce shard reads it (lib/transfer/shard_files.cpp):
// only the 1 MiB chunks that hold a marked row are read, each checked against its stored digest, and the digest
// table against the header's checksum. So a corrupted chunk that holds none of the rows is never read, and one
// that does is refused by name; the rows kept are the rows of the whole array.
#include "passes.h"
#include "transfer.h"

#include "core.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <unistd.h>

namespace fs = std::filesystem;

namespace prt {
namespace {

// 100,000 vertices of order 3, one channel: 900,000 floats, so the exitant section spans four 1 MiB chunks.
ShardRun bigRun() {
    ShardRun run;
    run.meshHash = "xxh128:00000000000000000000000000000000";
    run.vertexCount = 100000;
    run.triangleCount = 1;
    run.options.mode = TransferMode::Interreflected;
    run.options.order = 3;
    run.options.samples = 8;
    run.options.bounces = 2;
    run.channels = 1;
    run.rowEnd = run.vertexCount;
    return run;
}

class ShardExitant : public ::testing::Test {
protected:
    fs::path dir;
    ShardRun run = bigRun();
    std::vector<float> exitant; // [vertex][9]: vertex v's row holds v + i / 16

    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir = fs::temp_directory_path() / ("prt_shard_exitant_" + std::to_string(getpid()) + "_" + info->name());
        fs::remove_all(dir);
        fs::create_directories(dir);
        ShardRows rows;
        rows.rowBegin = 0;
        rows.rowEnd = run.vertexCount;
        rows.total.assign(run.vertexCount * 27, 0.25f);
        rows.direct.assign(run.vertexCount * 27, 0.125f);
        exitant.resize(run.vertexCount * 9);
        for (size_t i = 0; i < exitant.size(); ++i) exitant[i] = float(i / 9) + float(i % 9) / 16.0f;
        rows.exitant = exitant;
        writeShardRows(path("rows"), run, rows);
        gatherExitant({path("rows")}, run, path("exitant"));
    }
    void TearDown() override { fs::remove_all(dir); }
    std::string path(const std::string& name) const { return (dir / name).string(); }

    // The file with one bit of the exitant value at float index `value` flipped (still finite).
    std::string corruptedAt(size_t value) const {
        std::string file = readFileBytes(path("exitant"));
        uint32_t headerBytes;
        std::memcpy(&headerBytes, file.data() + 12, 4);
        file[16 + headerBytes + 4 * value] ^= 0x01;
        writeBytesAtomic(path("corrupt"), file);
        return path("corrupt");
    }
};

constexpr size_t kChunkFloats = (1 << 20) / 4; // 262,144: rows of 9 floats straddle the chunk boundaries

TEST_F(ShardExitant, KeepsTheMarkedRowsOfTheWholeArrayInVertexOrder) {
    std::vector<uint8_t> needed(run.vertexCount, 0);
    // A row on each side of the first chunk boundary, the row across it, the first and the last row.
    const size_t across = kChunkFloats / 9; // row 29,127 spans floats 262,143 .. 262,151
    for (size_t v : {size_t(0), across - 1, across, across + 1, size_t(run.vertexCount - 1)}) needed[v] = 1;
    const std::vector<float> kept = passes::readExitant(path("exitant"), run, 0, needed);
    std::vector<float> expected;
    for (size_t v = 0; v < run.vertexCount; ++v)
        if (needed[v]) expected.insert(expected.end(), exitant.begin() + 9 * v, exitant.begin() + 9 * (v + 1));
    EXPECT_EQ(kept, expected);
    EXPECT_TRUE(passes::readExitant(path("exitant"), run, 0, std::vector<uint8_t>(run.vertexCount, 0)).empty());
    EXPECT_EQ(passes::readExitant(path("exitant"), run, 0, std::vector<uint8_t>(run.vertexCount, 1)), exitant);
}

TEST_F(ShardExitant, ACorruptChunkIsRefusedByNameWhenReadAndNeverReadWhenNotNeeded) {
    const std::string corrupt = corruptedAt(2 * kChunkFloats + 5); // in chunk 2 only
    std::vector<uint8_t> firstRows(run.vertexCount, 0);
    for (size_t v = 0; v < 1000; ++v) firstRows[v] = 1; // chunk 0
    EXPECT_EQ(passes::readExitant(corrupt, run, 0, firstRows), passes::readExitant(path("exitant"), run, 0, firstRows));
    std::vector<uint8_t> chunkTwo(run.vertexCount, 0);
    chunkTwo[(2 * kChunkFloats + 5) / 9 + 100] = 1; // another row of chunk 2
    try {
        passes::readExitant(corrupt, run, 0, chunkTwo);
        FAIL() << "a corrupt chunk was read without an error";
    } catch (const Error& error) {
        const std::string message = error.what();
        EXPECT_NE(message.find(corrupt), std::string::npos) << message;
        EXPECT_NE(message.find("chunk 2 does not match its checksum"), std::string::npos) << message;
    }
}

} // namespace
} // namespace prt
