#include "core.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;

static fs::path scratch(const std::string& name) {
    fs::path dir = fs::temp_directory_path() / ("prt_core_test_" + std::to_string(getpid()));
    fs::create_directories(dir);
    return dir / name;
}

TEST(Core, ErrorNamesFilePlaceAndProblem) {
    prt::Error e("mesh.obj", "line 12", "index 99 out of range");
    EXPECT_STREQ(e.what(), "mesh.obj: line 12: index 99 out of range");
    EXPECT_EQ(e.exitCode(), prt::kExitInput);
    EXPECT_STREQ(prt::Error("a.exr", "", "not an image").what(), "a.exr: not an image");
}

TEST(Core, AtomicWriteLeavesNothingWhenWriterThrows) {
    fs::path target = scratch("artifact.bin");
    fs::remove(target);
    EXPECT_THROW(prt::writeFileAtomic(target.string(), [](const std::string& tmp) {
                     std::ofstream(tmp) << "partial";
                     throw prt::Error("", "", "simulated failure");
                 }),
                 prt::Error);
    EXPECT_FALSE(fs::exists(target));
    for (auto& entry : fs::directory_iterator(target.parent_path()))
        EXPECT_EQ(entry.path().filename().string().find(".artifact.bin.tmp"), std::string::npos) << entry.path();
}

TEST(Core, AtomicWriteReplacesWholeFile) {
    fs::path target = scratch("replace.txt");
    prt::writeBytesAtomic(target.string(), "first version, long");
    prt::writeBytesAtomic(target.string(), "second");
    EXPECT_EQ(prt::readFileBytes(target.string()), "second");
}

TEST(Core, WriteIntoMissingFolderFailsCleanly) {
    fs::path target = scratch("no/such/folder/out.bin");
    EXPECT_THROW(prt::writeBytesAtomic(target.string(), "x"), prt::Error);
    EXPECT_FALSE(fs::exists(target));
}

TEST(Core, MissingFileIsAnInputError) {
    try {
        prt::readFileBytes("/nonexistent/prt/file.glb");
        FAIL();
    } catch (const prt::Error& e) {
        EXPECT_EQ(e.file(), "/nonexistent/prt/file.glb");
        EXPECT_EQ(e.exitCode(), prt::kExitInput);
    }
}

TEST(Core, HashIsStableAndSensitive) {
    EXPECT_EQ(prt::hashBytes("abc", 3), prt::hashBytes("abc", 3));
    EXPECT_NE(prt::hashBytes("abc", 3), prt::hashBytes("abd", 3));
    EXPECT_EQ(prt::hashBytes("", 0).rfind("xxh128:", 0), 0u);
    fs::path file = scratch("hash.bin");
    std::string big(3 << 20, 'q'); // spans several read chunks
    big[123456] = 'z';
    prt::writeBytesAtomic(file.string(), big);
    EXPECT_EQ(prt::hashFile(file.string()), prt::hashBytes(big.data(), big.size()));
}

TEST(Core, NpyRoundTripAndValidation) {
    fs::path file = scratch("a.npy");
    std::vector<float> data = {1.f, -2.5f, 3.f, 4.f, 5.f, 6.f};
    prt::writeNpy(file.string(), data, {2, 3});
    std::vector<size_t> shape;
    EXPECT_EQ(prt::readNpy(file.string(), &shape), data);
    EXPECT_EQ(shape, (std::vector<size_t>{2, 3}));
    // Header must be 64-byte aligned as numpy writes it.
    std::string bytes = prt::readFileBytes(file.string());
    EXPECT_EQ((bytes.size() - data.size() * 4) % 64, 0u);
    // Truncated data is reported.
    prt::writeBytesAtomic(file.string(), bytes.substr(0, bytes.size() - 4));
    EXPECT_THROW(prt::readNpy(file.string(), &shape), prt::Error);
    prt::writeBytesAtomic(file.string(), "not numpy at all");
    EXPECT_THROW(prt::readNpy(file.string(), &shape), prt::Error);
}

TEST(Core, FileExtension) {
    EXPECT_EQ(prt::fileExtension("a/b/Mesh.GLB"), "glb");
    EXPECT_EQ(prt::fileExtension("a.b/mesh"), "");
    EXPECT_EQ(prt::fileExtension("x.tar.gz"), "gz");
}
