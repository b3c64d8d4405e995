// Image and environment-map reading, validation, and atomic writing.
#include "image.h"

#include "core.h"
#include "image_library.h"

#include <OpenImageIO/deepdata.h>
#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

class ImageTest : public testing::Test {
protected:
    void SetUp() override {
        folder = fs::temp_directory_path() /
                 ("prt-image-test-" + std::to_string(getpid()) + "-" +
                  testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(folder);
        fs::create_directories(folder);
    }
    void TearDown() override { fs::remove_all(folder); }
    std::string file(const std::string& name) const { return (folder / name).string(); }

    fs::path folder;
};

prt::Image gradient(int width, int height) {
    prt::Image image{width, height, std::vector<float>(size_t(width) * height * 3)};
    for (size_t i = 0; i < image.rgb.size(); ++i) image.rgb[i] = 0.001f * float(i) + 0.123f;
    return image;
}

// Runs `read` expecting a prt::Error whose message holds every one of `parts`.
template <typename Read>
void expectError(Read read, std::initializer_list<std::string> parts) {
    try {
        read();
        FAIL() << "no error thrown";
    } catch (const prt::Error& e) {
        EXPECT_EQ(e.exitCode(), prt::kExitInput);
        for (const std::string& part : parts)
            EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what() << " lacks " << part;
    }
}

} // namespace

TEST_F(ImageTest, FloatExrRoundTripsExactly) {
    prt::Image image = gradient(7, 5);
    std::string path = file("round.exr");
    prt::writeImage(path, image);
    prt::Image back = prt::readImage(path);
    EXPECT_EQ(back.width, 7);
    EXPECT_EQ(back.height, 5);
    EXPECT_EQ(back.rgb, image.rgb);
}

// Farms cache on bytes: the same pixels must give the same file, whenever written (no timestamp in the header).
TEST_F(ImageTest, SamePixelsWrittenLaterGiveTheSameBytes) {
    const char* names[] = {"a.exr", "a.png"};
    for (const char* name : names) prt::writeImage(file(std::string("first-") + name), gradient(5, 3), true);
    usleep(1100000); // across a second boundary, the resolution of EXR's capDate
    for (const char* name : names) {
        prt::writeImage(file(std::string("second-") + name), gradient(5, 3), true);
        EXPECT_EQ(prt::readFileBytes(file(std::string("first-") + name)),
                  prt::readFileBytes(file(std::string("second-") + name)))
            << name;
    }
}

TEST_F(ImageTest, HalfExrRoundTripsToHalfPrecision) {
    prt::Image image = gradient(6, 3);
    std::string path = file("half.exr");
    prt::writeImage(path, image, true);
    prt::Image back = prt::readImage(path);
    ASSERT_EQ(back.rgb.size(), image.rgb.size());
    for (size_t i = 0; i < image.rgb.size(); ++i) EXPECT_NEAR(back.rgb[i], image.rgb[i], image.rgb[i] * 1e-3f);
    bool lossy = false;
    for (size_t i = 0; i < image.rgb.size(); ++i) lossy |= back.rgb[i] != image.rgb[i];
    EXPECT_TRUE(lossy) << "values were not stored as half";
}

TEST_F(ImageTest, PngStoresEightBitsByExtension) {
    prt::Image image{3, 1, {0.0f, 0.25f, 0.5f, 0.75f, 1.0f, 0.1f, 0.2f, 0.3f, 0.4f}};
    std::string path = file("small.png");
    prt::writeImage(path, image);
    prt::Image back = prt::readImage(path);
    ASSERT_EQ(back.rgb.size(), image.rgb.size());
    for (size_t i = 0; i < image.rgb.size(); ++i) EXPECT_NEAR(back.rgb[i], image.rgb[i], 0.5f / 255.0f + 1e-6f);
}

TEST_F(ImageTest, WriteReplacesAtomicallyAndLeavesNoTemporaries) {
    std::string path = file("over.exr");
    prt::writeImage(path, gradient(4, 2));
    prt::Image second = gradient(2, 1);
    prt::writeImage(path, second);
    EXPECT_EQ(prt::readImage(path).rgb, second.rgb);
    int entries = 0;
    for (const auto& entry : fs::directory_iterator(folder)) entries += entry.is_regular_file();
    EXPECT_EQ(entries, 1);
}

TEST_F(ImageTest, WriteIntoMissingFolderFailsWithOutputError) {
    std::string path = file("missing/out.exr");
    try {
        prt::writeImage(path, gradient(2, 1));
        FAIL() << "no error thrown";
    } catch (const prt::Error& e) {
        EXPECT_EQ(e.exitCode(), prt::kExitOutput);
        EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
    }
    EXPECT_FALSE(fs::exists(path));
}

TEST_F(ImageTest, GreyImagesAreReplicated) {
    std::string path = file("grey.exr");
    std::vector<float> grey = {0.5f, 1.5f, 2.5f, 3.5f};
    auto output = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(output);
    ASSERT_TRUE(output->open(path, OIIO::ImageSpec(2, 2, 1, OIIO::TypeDesc::FLOAT)));
    ASSERT_TRUE(output->write_image(OIIO::TypeDesc::FLOAT, grey.data()));
    ASSERT_TRUE(output->close());
    prt::Image image = prt::readImage(path);
    ASSERT_EQ(image.rgb.size(), 12u);
    for (int p = 0; p < 4; ++p)
        for (int c = 0; c < 3; ++c) EXPECT_EQ(image.rgb[p * 3 + c], grey[p]);
}

TEST_F(ImageTest, MissingFileNamesTheFile) {
    std::string path = file("absent.exr");
    expectError([&] { prt::readImage(path); }, {path, "not found"});
    expectError([&] { prt::readEnvironmentMap(path); }, {path, "not found"});
}

// OpenImageIO would try its other readers on it (a PNG or HDR so named was read): refused by its magic number.
TEST_F(ImageTest, TextRenamedExrIsNotAnImage) {
    std::string path = file("notes.exr");
    std::ofstream(path) << "these are notes, not pixels\n";
    expectError([&] { prt::readImage(path); }, {path, "named .exr but not OpenEXR"});
    expectError([&] { prt::readEnvironmentMap(path); }, {path, "not OpenEXR"});
}

// A deep EXR stores per-pixel sample lists rather than an image: named as such, not misread.
TEST_F(ImageTest, DeepExrIsNotAnImage) {
    std::string path = file("deep.exr");
    OIIO::ImageSpec spec(2, 2, 1, OIIO::TypeDesc::FLOAT);
    spec.channelnames = {"Z"};
    spec.deep = true;
    OIIO::DeepData deep(spec);
    for (int p = 0; p < 4; ++p) deep.set_samples(p, 1);
    auto output = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(output);
    ASSERT_TRUE(output->open(path, spec));
    ASSERT_TRUE(output->write_deep_image(deep)) << output->geterror();
    ASSERT_TRUE(output->close());
    expectError([&] { prt::readImage(path); }, {path, "deep"});
}

TEST_F(ImageTest, TruncatedExrIsAnError) {
    std::string whole = file("whole.exr"), cut = file("cut.exr");
    prt::writeImage(whole, gradient(64, 32));
    std::string bytes = prt::readFileBytes(whole);
    std::ofstream(cut, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
    expectError([&] { prt::readEnvironmentMap(cut); }, {cut});
}

TEST_F(ImageTest, EnvironmentLayoutFollowsAspectRatio) {
    std::string equirect = file("latlong.exr"), cube = file("cube.exr"), square = file("square.exr");
    prt::writeImage(equirect, gradient(8, 4));
    prt::writeImage(cube, gradient(4, 24));
    prt::writeImage(square, gradient(4, 4));
    EXPECT_EQ(prt::readEnvironmentMap(equirect).layout, prt::EnvLayout::Equirectangular);
    EXPECT_EQ(prt::readEnvironmentMap(cube).layout, prt::EnvLayout::CubeStrip);
    expectError([&] { prt::readEnvironmentMap(square); }, {square, "4x4", "2:1"});
}

TEST_F(ImageTest, BadTexelsNameFileAndFirstTexel) {
    struct Case {
        float value;
        const char* problem;
    };
    for (Case bad : {Case{std::numeric_limits<float>::quiet_NaN(), "NaN"},
                     Case{-0.5f, "negative"},
                     Case{std::numeric_limits<float>::infinity(), "infinite"}}) {
        prt::Image image = gradient(8, 4);
        image.rgb[(3 * 8 + 5) * 3 + 1] = bad.value; // texel (5, 3), green
        image.rgb[(3 * 8 + 6) * 3 + 0] = bad.value; // a later one, not reported
        std::string path = file(std::string(bad.problem) + ".exr");
        prt::writeImage(path, image);
        expectError([&] { prt::readEnvironmentMap(path); }, {path, "texel (5, 3) channel 1", bad.problem});
        EXPECT_EQ(prt::readImage(path).width, 8) << "plain images are not validated";
    }
}

// DWA-compressed maps undershoot zero slightly near bright texels; that noise is clamped, not rejected.
TEST_F(ImageTest, CompressionNoiseBelowZeroIsClampedToZero) {
    prt::Image image = gradient(8, 4);
    image.rgb[7] = -0.001f; // the mean is about 0.17
    std::string path = file("noisy.exr");
    prt::writeImage(path, image);
    prt::EnvironmentMap env = prt::readEnvironmentMap(path);
    EXPECT_EQ(env.radiance.rgb[7], 0.0f);
    EXPECT_EQ(env.radiance.rgb[8], image.rgb[8]);
}

// Found by fuzz_exr: a 291-byte EXR whose string attribute declares 1.9 GB made OpenEXR allocate it. The header
// check refuses it first, naming the attribute.
TEST(Image, ExrAttributeLargerThanTheFileIsRefusedBeforeOpenExrAllocates) {
    std::string path = std::string(PRT_SOURCE_DIR) + "/tests/fuzz/corpus/exr/attribute-size-past-the-end.exr";
    try {
        prt::readEnvironmentMap(path);
        FAIL() << "expected an error";
    } catch (const prt::Error& e) {
        EXPECT_EQ(e.exitCode(), prt::kExitInput);
        EXPECT_NE(std::string(e.what()).find("attribute 'Exif:ImageHistory' (string) declares 1886220131 bytes"),
                  std::string::npos)
            << e.what();
    }
}

// OpenEXR also trusts the sizes inside two attribute types: a preview image's width x height, and each string of a
// string vector. Each is refused before OpenImageIO opens the file, naming the attribute.
TEST_F(ImageTest, ExrPreviewAndStringVectorSizesAreCheckedBeforeOpenExrAllocates) {
    prt::Image image;
    image.width = 4, image.height = 2;
    image.rgb.assign(4 * 2 * 3, 1.0f);
    std::string good = file("good.exr");
    prt::writeImage(good, image);
    std::string bytes = prt::readFileBytes(good);
    auto withAttribute = [&](const std::string& name, const std::string& type, const std::string& value) {
        std::string attribute = name + '\0' + type + '\0';
        uint32_t size = uint32_t(value.size());
        attribute.append(reinterpret_cast<const char*>(&size), 4);
        attribute += value;
        std::string out = bytes;
        out.insert(8, attribute); // attributes may come in any order; the header check runs before any pixel
        std::string path = file(name + ".exr");
        prt::writeBytesAtomic(path, out);
        return path;
    };
    auto words = [](std::initializer_list<uint32_t> values) {
        std::string out;
        for (uint32_t v : values) out.append(reinterpret_cast<const char*>(&v), 4);
        return out;
    };
    struct Case {
        std::string path, says;
    };
    for (const Case& c : {Case{withAttribute("thumb", "preview", words({65536, 65536})), "65536 x 65536 pixels"},
                          Case{withAttribute("notes", "stringvector", words({1000000000, 0})), "1000000000 bytes"},
                          Case{withAttribute("cut", "stringvector", std::string("\x02\x00", 2)), "ends inside a length"}}) {
        try {
            prt::readEnvironmentMap(c.path);
            ADD_FAILURE() << c.path << ": expected an error";
        } catch (const prt::Error& e) {
            EXPECT_EQ(e.exitCode(), prt::kExitInput);
            EXPECT_NE(std::string(e.what()).find(c.says), std::string::npos) << e.what();
        }
    }
    // A well-formed preview and string vector pass the check (the insertion shifts the pixel offsets, so the file
    // itself no longer reads).
    EXPECT_NO_THROW(prt::checkExrHeaders(withAttribute("fine", "preview", words({1, 1}) + std::string(4, '\x7f'))));
    EXPECT_NO_THROW(prt::checkExrHeaders(withAttribute("list", "stringvector", words({2}) + "ab" + words({0}))));
}

// Where prt looks for its OpenImageIO module (image_library.h): next to the executable, then an installed lib/prt/
// beside its bin/, then this build tree's, then the configured install prefix's; the first that exists wins.
TEST(ImageModule, CandidatesInTheDocumentedOrder) {
    std::vector<std::string> candidates = prt::imageModuleCandidates("/opt/engine/bin/game");
    ASSERT_EQ(candidates.size(), 4u);
    EXPECT_EQ(candidates[0], "/opt/engine/bin/prt_oiio.so");
    EXPECT_EQ(candidates[1], "/opt/engine/lib/prt/prt_oiio.so");
    EXPECT_EQ(candidates[2], std::string(PRT_BINARY_DIR) + "/prt_oiio.so");
    EXPECT_NE(candidates[3].find("/lib"), std::string::npos);
    EXPECT_EQ(candidates[3].substr(candidates[3].size() - 16), "/prt/prt_oiio.so");
    // Nothing at the first two: the build tree's module is found.
    EXPECT_EQ(prt::findImageModule("/nonexistent/bin/game"), std::string(PRT_BINARY_DIR) + "/prt_oiio.so");
    // The version the module reports is the one its OpenImageIO headers say (this test includes the same ones).
    EXPECT_EQ(prt::imageLibraryVersion(), OIIO_VERSION_STRING);
}
