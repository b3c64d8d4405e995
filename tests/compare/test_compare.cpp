#include "compare.h"

#include "core.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

namespace {

std::string tempPath(const std::string& name) {
    std::filesystem::path folder = std::filesystem::temp_directory_path() / "prt_test_compare";
    std::filesystem::create_directories(folder);
    return (folder / name).string();
}

TEST(Compare, IdenticalArraysHaveZeroError) {
    std::vector<float> a = {0.1f, 0.2f, 0.3f, 4.0f, 5.0f, 6.0f, 0.0f, 7.5f, 1.0f};
    prt::ErrorMetrics m = prt::compareRadiance(a.data(), a.data(), 3);
    EXPECT_EQ(m.count, 3u);
    EXPECT_EQ(m.rmse, 0.0);
    EXPECT_EQ(m.relativeRmse, 0.0);
    EXPECT_EQ(m.nrmse, 0.0);
    EXPECT_EQ(m.maxAbsError, 0.0);
    EXPECT_EQ(m.meanAbsLuminanceError, 0.0);
    EXPECT_EQ(m.meanLuminanceBias, 0.0);
}

TEST(Compare, KnownDifferencesGiveKnownMetrics) {
    // Reference rows (1,1,1) and (3,3,3); the result adds +1 to every channel of row 0 and -2 to the red of row 1.
    std::vector<float> reference = {1, 1, 1, 3, 3, 3};
    std::vector<float> result = {2, 2, 2, 1, 3, 3};
    prt::ErrorMetrics m = prt::compareRadiance(result.data(), reference.data(), 2);
    double rmse = std::sqrt((3.0 * 1.0 + 4.0) / 6.0);
    EXPECT_DOUBLE_EQ(m.rmse, rmse);
    EXPECT_DOUBLE_EQ(m.relativeRmse, rmse / std::sqrt((3.0 + 27.0) / 6.0));
    EXPECT_DOUBLE_EQ(m.nrmse, rmse / 2.0);
    EXPECT_DOUBLE_EQ(m.maxAbsError, 2.0);
    // Luminance errors: row 0 +1 (weights sum to 1), row 1 -2 * 0.2126.
    EXPECT_NEAR(m.meanAbsLuminanceError, (1.0 + 2.0 * 0.2126) / 2.0, 1e-12);
    EXPECT_NEAR(m.meanLuminanceBias, (1.0 - 2.0 * 0.2126) / 2.0, 1e-12);
}

TEST(Compare, FlatReferenceNormalisesToInfinityOnlyWhenThereIsError) {
    std::vector<float> reference = {0, 0, 0};
    std::vector<float> result = {0, 0, 1};
    prt::ErrorMetrics same = prt::compareRadiance(reference.data(), reference.data(), 1);
    EXPECT_EQ(same.relativeRmse, 0.0);
    EXPECT_EQ(same.nrmse, 0.0);
    prt::ErrorMetrics different = prt::compareRadiance(result.data(), reference.data(), 1);
    EXPECT_EQ(different.relativeRmse, std::numeric_limits<double>::infinity());
    EXPECT_EQ(different.nrmse, std::numeric_limits<double>::infinity());
}

TEST(Compare, CsvAndNpyRoundTripBitExact) {
    std::vector<float> rgb = {0.1f, 1e-20f, 3.4028e38f, 123456.789f, 0.0f, 1.0f / 3.0f};
    for (const char* name : {"roundtrip.csv", "roundtrip.npy"}) {
        std::string path = tempPath(name);
        prt::writeVertexRadiance(path, rgb);
        EXPECT_EQ(prt::readVertexRadiance(path), rgb) << name;
    }
    prt::ErrorMetrics m = prt::compareFiles(tempPath("roundtrip.csv"), tempPath("roundtrip.npy"));
    EXPECT_EQ(m.count, 2u);
    EXPECT_EQ(m.maxAbsError, 0.0);
}

TEST(Compare, CsvHeaderIsOptional) {
    std::string path = tempPath("noheader.csv");
    prt::writeBytesAtomic(path, "1,2,3\n 4 , 5 , 6 \r\n\n");
    EXPECT_EQ(prt::readVertexRadiance(path), (std::vector<float>{1, 2, 3, 4, 5, 6}));
}

TEST(Compare, ShapeMismatchNamesBothFiles) {
    std::string a = tempPath("two.npy"), b = tempPath("three.npy");
    prt::writeVertexRadiance(a, std::vector<float>(6, 1.0f));
    prt::writeVertexRadiance(b, std::vector<float>(9, 1.0f));
    try {
        prt::compareFiles(a, b);
        FAIL() << "no error";
    } catch (const prt::Error& e) {
        EXPECT_NE(std::string(e.what()).find(a), std::string::npos);
        EXPECT_NE(std::string(e.what()).find(b), std::string::npos);
    }
}

TEST(Compare, BadFilesThrow) {
    std::string badRow = tempPath("badrow.csv");
    prt::writeBytesAtomic(badRow, "r,g,b\n1,2,3\n1,2\n");
    try {
        prt::readVertexRadiance(badRow);
        FAIL() << "no error";
    } catch (const prt::Error& e) {
        EXPECT_EQ(e.file(), badRow);
        EXPECT_EQ(e.place(), "line 3");
    }
    std::string nan = tempPath("nan.csv");
    prt::writeBytesAtomic(nan, "nan,1,2\n");
    EXPECT_THROW(prt::readVertexRadiance(nan), prt::Error);
    std::string wrongShape = tempPath("wrongshape.npy");
    prt::writeNpy(wrongShape, std::vector<float>(8, 0.0f), {2, 4});
    EXPECT_THROW(prt::readVertexRadiance(wrongShape), prt::Error);
    std::string notNpy = tempPath("garbage.npy");
    prt::writeBytesAtomic(notNpy, "not a numpy file");
    EXPECT_THROW(prt::readVertexRadiance(notNpy), prt::Error);
    EXPECT_THROW(prt::readVertexRadiance(tempPath("missing.csv")), prt::Error);
    EXPECT_THROW(prt::readVertexRadiance(tempPath("radiance.txt")), prt::Error);
    EXPECT_THROW(prt::writeVertexRadiance(tempPath("radiance.txt"), {1, 2, 3}), prt::Error);
}

} // namespace
