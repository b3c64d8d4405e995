// The hybrid relight of a scene bundle (docs/bundle.md "Scene bundles"), end to end through the CLI: a textured
// floor under two instances of one slab (one mirrored) and a wholly cut-out slab (MASK), lit by a single cone
// light with a zero SH residual, so
// every answer is in closed form: radiance = albedo / pi * L * C(n . d, r) * V with C = pi sin^2 r for n = d; the
// floor under a slab sees none of the cone (V = 0), the open floor, the floor under the cut-out and the slabs' tops
// all of it (V = 1). The
// picture (`--image`) multiplies the lights at albedo 1 by the material's base colour per pixel (a nearest-texel
// checker on the floor), as `prt render` draws a scene. The turn table (--visibility-turns) of a tilted light equals
// the single-turn visibility cast at each table turn by --rotate-y.
#include "cli_util.h"
#include "scene.h"
#include "scene_gltf.h"

#include "core.h"
#include "image.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>

#include <unistd.h>

namespace fs = std::filesystem;
using nlohmann::json;
using prt::test::CliRun;

namespace {

constexpr double kRadius = 0.1;          // the cone's angular radius
constexpr float kRadiance = 2.0f;        // its radiance, every channel
constexpr float kSlabHeight = 0.6f;      // the slabs' height above the floor
const float kSlabColour[3] = {0.5f, 0.7f, 0.9f};
const float kSlabX[2] = {-1.0f, 1.0f};   // the slabs' centres (side 1, z = 0); the second is mirrored in x
constexpr float kCutoutHeight = 0.5f, kCutoutZ = 1.2f; // a third slab (side 1, x = 0), wholly cut out (MASK)
constexpr size_t kRows = 17 * 17 + 3 * 9; // the floor, then each slab instance its own rows

// sRGB 8-bit to linear (the glTF texture's decoding).
float srgbLinear(int value) {
    double c = value / 255.0;
    return float(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
}

// The floor's 2 x 2 checker: texel (column, row) = red, green / blue, grey (u along +X, v along +Z).
std::array<float, 3> floorAlbedo(float x, float z) {
    const int column = x > 0.0f, row = z > 0.0f;
    const float grey = srgbLinear(188);
    const std::array<float, 3> texels[2][2] = {{{{1, 0, 0}}, {{0, 1, 0}}}, {{{0, 0, 1}}, {{grey, grey, grey}}}};
    return texels[row][column];
}

// Chebyshev distance from (x, z) to the nearest slab's footprint (negative inside).
float slabDistance(float x, float z) {
    float best = 1e9f;
    for (float cx : kSlabX) best = std::min(best, std::max(std::abs(x - cx), std::abs(z)) - 0.5f);
    return best;
}

class SceneHybrid : public ::testing::Test {
protected:
    void SetUp() override {
        dir = fs::temp_directory_path() / ("prt_scene_hybrid_" + std::to_string(getpid()));
        fs::create_directories(dir);
        prt::test::TestScene scene;
        scene.meshes = {{{prt::makePlane(4.0f, 16, 0.0f), 0}}, {{prt::makePlane(1.0f, 2, 0.0f), 1}},
                        {{prt::makePlane(1.0f, 2, 0.0f), 2}}};
        scene.nodes = json::array({{{"mesh", 0}},
                                   {{"mesh", 1}, {"translation", {kSlabX[0], kSlabHeight, 0.0}}},
                                   {{"mesh", 1},
                                    {"translation", {kSlabX[1], kSlabHeight, 0.0}},
                                    {"scale", {-1.0, 1.0, 1.0}}},
                                   {{"mesh", 2}, {"translation", {0.0, kCutoutHeight, kCutoutZ}}}});
        scene.roots = {0, 1, 2, 3};
        scene.materials = json::array(
            {{{"pbrMetallicRoughness", {{"metallicFactor", 0.0}, {"baseColorTexture", {{"index", 0}}}}}},
             {{"pbrMetallicRoughness",
               {{"metallicFactor", 0.0}, {"baseColorFactor", {kSlabColour[0], kSlabColour[1], kSlabColour[2], 1.0}}}}},
             // Cut out everywhere (alpha 0.2 below the cutoff 0.5): no shadow, no picture.
             {{"alphaMode", "MASK"},
              {"pbrMetallicRoughness", {{"metallicFactor", 0.0}, {"baseColorFactor", {0.0, 0.0, 1.0, 0.2}}}}}});
        scene.textures = json::array({{{"source", 0}, {"sampler", 0}}});
        scene.samplers = json::array({{{"magFilter", 9728}, {"minFilter", 9728}}});
        const std::vector<uint8_t> checker = {255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 188, 188, 188, 255};
        scene.images = json::array({{{"uri", prt::test::pngDataUri(prt::test::pngBytes(2, 2, checker))}}});
        prt::test::writeSceneGltf(path("scene.gltf"), scene);
        ASSERT_EQ(run("meshprep " + path("scene.gltf") + " -o " + path("prepped.glb")).exitCode, 0);
        CliRun transfer = run("transfer " + path("prepped.glb") + " -o " + path("scene.prt.glb") +
                              " --mode shadowed --order 2 --samples 16");
        ASSERT_EQ(transfer.exitCode, 0) << transfer.stderrText;
    }
    void TearDown() override { fs::remove_all(dir); }

    std::string path(const std::string& name) const { return (dir / name).string(); }
    CliRun run(const std::string& arguments) { return prt::test::runPrt(arguments, dir); }
    // A prt-lights JSON of order 2 with a zero residual and one cone of kRadius toward `d`.
    std::string writeLights(const std::string& name, std::array<double, 3> d) {
        json lights = {{"format", "prt-lights"}, {"order", 2},
                       {"residual", json::array({{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}})},
                       {"lights", json::array({{{"direction", d}, {"radiance", {kRadiance, kRadiance, kRadiance}},
                                                {"angular_radius", kRadius}}})}};
        std::ofstream(path(name)) << lights.dump();
        return path(name);
    }
    fs::path dir;
};

} // namespace

TEST_F(SceneHybrid, ConeBlockedByAnInstanceIsZeroAndOpenRowsAreInClosedForm) {
    std::string lights = writeLights("up.lights.json", {0.0, 1.0, 0.0});
    CliRun r = run("relight " + path("scene.prt.glb") + " --lights " + lights + " --visibility-out " +
                   path("visibility.npy") + " -o " + path("radiance.npy"));
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    prt::Bundle bundle = prt::readBundle(path("scene.prt.glb"));
    const prt::Layer* albedoLayer = prt::findLayer(bundle, "diffuse_albedo");
    ASSERT_NE(albedoLayer, nullptr);
    const size_t rows = bundle.mesh.vertexCount();
    ASSERT_EQ(rows, kRows);
    std::vector<size_t> shape;
    std::vector<float> visibility = prt::readNpy(path("visibility.npy"), &shape);
    ASSERT_EQ(shape, (std::vector<size_t>{rows, 1}));
    std::vector<float> radiance = prt::readNpy(path("radiance.npy"), &shape);
    ASSERT_EQ(shape, (std::vector<size_t>{rows, 3}));
    const float open = float(kRadiance * std::sin(kRadius) * std::sin(kRadius)); // L C / pi at albedo 1, n = d
    const float penumbra = float(kSlabHeight * std::tan(kRadius)) + 0.02f;
    int blocked = 0, unblocked = 0, tops = 0, underCutout = 0;
    for (size_t v = 0; v < rows; ++v) {
        const float* p = &bundle.mesh.positions[3 * v];
        const float* albedo = &albedoLayer->data[3 * v];
        float expectedVisibility;
        if (std::abs(p[1] - kSlabHeight) < 1e-4f) {
            expectedVisibility = 1.0f, ++tops;
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(albedo[c], kSlabColour[c], 1e-6f) << "row " << v;
        } else if (slabDistance(p[0], p[2]) < -penumbra) {
            expectedVisibility = 0.0f, ++blocked;
        } else if (slabDistance(p[0], p[2]) > penumbra) {
            expectedVisibility = 1.0f, ++unblocked;
        } else {
            continue; // in a penumbra
        }
        // The floor under the cut-out slab sees the whole cone: the rays pass through it, as the transfer's do.
        if (p[1] == 0.0f && std::abs(p[0]) < 0.42f && std::abs(p[2] - kCutoutZ) < 0.42f) {
            EXPECT_EQ(visibility[v], 1.0f) << "row " << v << " under the cut-out";
            ++underCutout;
        }
        EXPECT_EQ(visibility[v], expectedVisibility) << "row " << v << " at " << p[0] << "," << p[1] << "," << p[2];
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(radiance[3 * v + c], albedo[c] * open * expectedVisibility, 1e-5f * open) << "row " << v;
    }
    EXPECT_EQ(tops, 18);
    EXPECT_GE(blocked, 2 * 9);   // the floor vertices strictly under each slab
    EXPECT_GE(unblocked, 200);
    EXPECT_EQ(underCutout, 9);
}

TEST_F(SceneHybrid, PictureIsTheLightsTimesTheBaseColourPerPixel) {
    std::string lights = writeLights("up.lights.json", {0.0, 1.0, 0.0});
    const int size = 64;
    const double fovy = 40.0, height = 6.0;
    CliRun r = run("relight " + path("scene.prt.glb") + " --lights " + lights + " --image " + std::to_string(size) +
                   "," + std::to_string(size) + " --camera 0,6,0,0,0,0,0,0,-1,40 -o " + path("picture.exr"));
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    prt::Image picture = prt::readImage(path("picture.exr"));
    ASSERT_EQ(picture.width, size);
    ASSERT_EQ(picture.height, size);
    const float open = float(kRadiance * std::sin(kRadius) * std::sin(kRadius));
    const double halfHeight = std::tan(fovy * M_PI / 360.0);
    int floorPixels = 0, slabPixels[2] = {0, 0};
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            // From above with up = -Z: right is +X, down is +Z.
            const double sx = (2.0 * (x + 0.5) / size - 1.0) * halfHeight;
            const double sz = (2.0 * (y + 0.5) / size - 1.0) * halfHeight;
            const float* pixel = &picture.rgb[3 * (size_t(y) * size + x)];
            const float topX = float(sx * (height - kSlabHeight)), topZ = float(sz * (height - kSlabHeight));
            const float floorX = float(sx * height), floorZ = float(sz * height);
            std::array<float, 3> want;
            if (slabDistance(topX, topZ) < -0.03f) {
                want = {kSlabColour[0], kSlabColour[1], kSlabColour[2]};
                ++slabPixels[topX > 0.0f];
            } else if (slabDistance(topX, topZ) > 0.03f && slabDistance(floorX, floorZ) > 0.4f &&
                       std::abs(floorX) > 0.05f && std::abs(floorZ) > 0.05f && std::abs(floorX) < 1.95f &&
                       std::abs(floorZ) < 1.95f) {
                // Every corner of the floor triangle under this pixel is open (the grid is 0.25 apart).
                want = floorAlbedo(floorX, floorZ);
                ++floorPixels;
            } else {
                continue;
            }
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(pixel[c], want[c] * open, 1e-5f * open) << "pixel " << x << "," << y << " channel " << c;
        }
    EXPECT_GE(floorPixels, 1000);
    EXPECT_GE(slabPixels[0], 40); // the plain instance
    EXPECT_GE(slabPixels[1], 40); // the mirrored one keeps its front
}

TEST_F(SceneHybrid, TurnTableIsTheVisibilityCastAtEachTurn) {
    std::string lights = writeLights("tilted.lights.json", {0.6, 0.8, 0.0});
    const int turns = 4;
    CliRun r = run("relight " + path("scene.prt.glb") + " --lights " + lights + " --visibility-out " +
                   path("table.npy") + " --visibility-turns " + std::to_string(turns) + " -o " + path("turn0.npy"));
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    std::ifstream in(path("table.npy"), std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_GT(bytes.size(), 10u);
    const size_t headerLength = uint8_t(bytes[8]) | (size_t(uint8_t(bytes[9])) << 8);
    const std::string header = bytes.substr(10, headerLength);
    const size_t rows = kRows;
    EXPECT_NE(header.find("'|u1'"), std::string::npos) << header;
    EXPECT_NE(header.find("(4," + std::to_string(rows) + ",1)"), std::string::npos) << header;
    ASSERT_EQ(bytes.size(), 10 + headerLength + turns * rows);
    const unsigned char* table = reinterpret_cast<const unsigned char*>(bytes.data()) + 10 + headerLength;
    for (int t = 0; t < turns; ++t) {
        const std::string single = path("v" + std::to_string(t) + ".npy");
        CliRun cast = run("relight " + path("scene.prt.glb") + " --lights " + lights + " --rotate-y " +
                          std::to_string(t * 360 / turns) + " --visibility-out " + single + " -o " + path("r.npy"));
        ASSERT_EQ(cast.exitCode, 0) << cast.stderrText;
        std::vector<size_t> shape;
        std::vector<float> visibility = prt::readNpy(single, &shape);
        ASSERT_EQ(visibility.size(), rows);
        int shadowed = 0;
        for (size_t v = 0; v < rows; ++v) {
            EXPECT_EQ(int(table[t * rows + v]), int(std::lround(255.0f * visibility[v])))
                << "turn " << t << " row " << v;
            shadowed += visibility[v] == 0.0f;
        }
        EXPECT_GT(shadowed, 0) << "turn " << t; // the slabs cast shadows at every turn
    }
}

// A bake's texel hybrid drawn by `--texels --image`: `prt scene plane` (side 2 at y = 0) baked at albedo 0.8 under
// the cone straight up, zero residual: every texel, and so every pixel on the plane, is 0.8 L sin^2 r; off it 0.
TEST_F(SceneHybrid, BakePictureIsTheTexelHybridAsRenderTexelsDrawsIt) {
    std::string lights = writeLights("up.lights.json", {0.0, 1.0, 0.0});
    ASSERT_EQ(run("scene plane -o " + path("plane.glb")).exitCode, 0);
    CliRun bake = run("bake " + path("plane.glb") + " -o " + path("plane.bake.glb") +
                      " --resolution 32 --order 2 --samples 16 --albedo 0.8 --format bundle");
    ASSERT_EQ(bake.exitCode, 0) << bake.stderrText;
    const int size = 48;
    CliRun r = run("relight " + path("plane.bake.glb") + " --texels --lights " + lights + " --image " +
                   std::to_string(size) + "," + std::to_string(size) + " --camera 0,4,0,0,0,0,0,0,-1,40 -o " +
                   path("bake.exr"));
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    prt::Image picture = prt::readImage(path("bake.exr"));
    ASSERT_EQ(picture.width, size);
    const float want = float(0.8 * kRadiance * std::sin(kRadius) * std::sin(kRadius));
    const double halfHeight = std::tan(40.0 * M_PI / 360.0);
    int on = 0, off = 0;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const double px = (2.0 * (x + 0.5) / size - 1.0) * halfHeight * 4.0;
            const double pz = (2.0 * (y + 0.5) / size - 1.0) * halfHeight * 4.0;
            const float* pixel = &picture.rgb[3 * (size_t(y) * size + x)];
            const double edge = std::max(std::abs(px), std::abs(pz));
            if (std::abs(edge - 1.0) < 0.05) continue; // the plane's border
            const float expected = edge < 1.0 ? want : 0.0f;
            (edge < 1.0 ? on : off) += 1;
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(pixel[c], expected, 1e-5f * want) << "pixel " << x << "," << y;
        }
    EXPECT_GE(on, 800);
    EXPECT_GE(off, 400);
    // Without --lights a picture of texels stays prt render's.
    EXPECT_EQ(run("relight " + path("plane.bake.glb") + " --texels --sh " + lights + " --image 8,8 --camera "
                  "0,4,0,0,0,0,0,0,-1,40 -o " + path("x.exr")).exitCode, 2);
}

// A scene bake (texel hybrid of irradiance transfer) drawn by `--texels --image`: the texels relit at albedo 1 times
// the materials per pixel, as `prt render --texels` draws a scene bake: the floor's checker and the slabs' colour
// times L sin^2 r where the cone is open.
TEST_F(SceneHybrid, SceneBakePictureIsTheLightsTimesTheBaseColourPerPixel) {
    std::string lights = writeLights("up.lights.json", {0.0, 1.0, 0.0});
    CliRun bake = run("bake " + path("prepped.glb") + " -o " + path("scene.bake.glb") +
                      " --resolution 128 --order 2 --samples 16 --format bundle");
    ASSERT_EQ(bake.exitCode, 0) << bake.stderrText;
    const int size = 64;
    const double fovy = 40.0, height = 6.0;
    CliRun r = run("relight " + path("scene.bake.glb") + " --texels --lights " + lights + " --image " +
                   std::to_string(size) + "," + std::to_string(size) + " --camera 0,6,0,0,0,0,0,0,-1,40 -o " +
                   path("scene_bake.exr"));
    ASSERT_EQ(r.exitCode, 0) << r.stderrText;
    prt::Image picture = prt::readImage(path("scene_bake.exr"));
    ASSERT_EQ(picture.width, size);
    const float open = float(kRadiance * std::sin(kRadius) * std::sin(kRadius));
    const double halfHeight = std::tan(fovy * M_PI / 360.0);
    int floorPixels = 0, slabPixels = 0;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            const double sx = (2.0 * (x + 0.5) / size - 1.0) * halfHeight;
            const double sz = (2.0 * (y + 0.5) / size - 1.0) * halfHeight;
            const float* pixel = &picture.rgb[3 * (size_t(y) * size + x)];
            const float topX = float(sx * (height - kSlabHeight)), topZ = float(sz * (height - kSlabHeight));
            const float floorX = float(sx * height), floorZ = float(sz * height);
            std::array<float, 3> want;
            if (slabDistance(topX, topZ) < -0.05f) {
                want = {kSlabColour[0], kSlabColour[1], kSlabColour[2]};
                ++slabPixels;
            } else if (slabDistance(topX, topZ) > 0.05f && slabDistance(floorX, floorZ) > 0.2f &&
                       std::abs(floorX) > 0.05f && std::abs(floorZ) > 0.05f && std::abs(floorX) < 1.95f &&
                       std::abs(floorZ) < 1.95f) {
                want = floorAlbedo(floorX, floorZ); // texels away from the shadows: all open
                ++floorPixels;
            } else {
                continue;
            }
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(pixel[c], want[c] * open, 1e-4f * open) << "pixel " << x << "," << y << " channel " << c;
        }
    EXPECT_GE(floorPixels, 1000);
    EXPECT_GE(slabPixels, 80);
}
