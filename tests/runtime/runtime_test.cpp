// The runtime against closed forms: hand-computed dot products, rotation identities, the white furnace,
// streaming ranges, and the errors an engine sees for bad bundles and lighting.
#include "runtime.h"

#include "core.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <span>
#include <stdexcept>

#include <sys/mman.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

// A folder of this process's own, removed with everything in it when the test ends.
struct ScratchDir {
    fs::path path = fs::temp_directory_path() / ("prt_runtime_test_" + std::to_string(getpid()));
    ScratchDir() { fs::create_directories(path); }
    ~ScratchDir() { fs::remove_all(path); }
};

// A bundle whose mesh has `positions` (one triangle, enough for a valid glTF) and a transfer layer of `order`.
prt::Bundle transferBundle(const std::vector<float>& positions, int order, std::vector<float> transfer) {
    prt::Bundle bundle;
    bundle.mesh.positions = positions;
    bundle.mesh.indices = {0, 1, 2};
    prt::Layer layer;
    layer.name = "transfer";
    layer.domain = "vertex";
    layer.semantic = "sh_transfer_rgb";
    layer.shape = {positions.size() / 3, uint64_t(order) * order, 3};
    layer.data = std::move(transfer);
    layer.params = {{"order", order}};
    bundle.layers.push_back(std::move(layer));
    return bundle;
}

std::vector<float> randomValues(size_t count, uint32_t seed) {
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
    std::vector<float> values(count);
    for (float& value : values) value = uniform(random);
    return values;
}

prt::RelightModel randomModel(uint32_t vertexCount, int order, uint32_t seed) {
    prt::RelightModel model;
    model.vertexCount = vertexCount;
    model.order = order;
    model.transfer = randomValues(size_t(vertexCount) * order * order * 3, seed);
    return model;
}

// The contraction in double, straight from docs/conventions.md.
std::vector<double> referenceRadiance(const prt::RelightModel& model, const float* lighting) {
    int n = model.order * model.order;
    std::vector<double> radiance(size_t(model.vertexCount) * 3, 0.0);
    for (size_t v = 0; v < model.vertexCount; ++v)
        for (int j = 0; j < n; ++j)
            for (int c = 0; c < 3; ++c)
                radiance[v * 3 + c] += double(model.transfer[(v * n + j) * 3 + c]) * lighting[j * 3 + c];
    return radiance;
}

// An equirectangular environment with an off-axis bright lobe, a colour gradient and no symmetry about +Y.
prt::EnvironmentMap lobeEnvironment(int width) {
    prt::EnvironmentMap env;
    env.radiance.width = width;
    env.radiance.height = width / 2;
    env.radiance.rgb.resize(size_t(width) * width / 2 * 3);
    const double lobe[3] = {0.48, 0.6, -0.64};
    for (int y = 0; y < width / 2; ++y)
        for (int x = 0; x < width; ++x) {
            double d[3];
            prt::sh::equirectDirection(width, width / 2, x, y, d);
            double cosine = d[0] * lobe[0] + d[1] * lobe[1] + d[2] * lobe[2];
            float* pixel = &env.radiance.rgb[(size_t(y) * width + x) * 3];
            pixel[0] = float(0.2 + 3.0 * std::pow(std::max(cosine, 0.0), 8.0));
            pixel[1] = float(0.5 + 0.4 * d[0]);
            pixel[2] = float(0.6 + 0.3 * d[2] * d[1]);
        }
    return env;
}

// The environment turned by R in pixel space: pixel d of the result shows the source's pixel at R^T d.
prt::EnvironmentMap rotateInPixels(const prt::EnvironmentMap& env, const double R[9]) {
    int width = env.radiance.width, height = env.radiance.height;
    prt::EnvironmentMap rotated = env;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            double d[3], s[3];
            prt::sh::equirectDirection(width, height, x, y, d);
            for (int i = 0; i < 3; ++i) s[i] = R[0 * 3 + i] * d[0] + R[1 * 3 + i] * d[1] + R[2 * 3 + i] * d[2];
            // Inverse of the equirect mapping of docs/conventions.md.
            double theta = std::acos(std::clamp(s[1], -1.0, 1.0)), phi = std::atan2(s[0], -s[2]);
            int sx = int(std::lround((phi + std::numbers::pi) / (2 * std::numbers::pi) * width - 0.5)) % width;
            int sy = int(std::lround(theta / std::numbers::pi * height - 0.5));
            for (int c = 0; c < 3; ++c)
                rotated.radiance.rgb[(size_t(y) * width + x) * 3 + c] =
                    env.radiance.rgb[(size_t(sy) * width + (sx + width) % width) * 3 + c];
        }
    return rotated;
}

double maxAbs(const std::vector<float>& values) {
    double m = 0.0;
    for (float value : values) m = std::max(m, double(std::fabs(value)));
    return m;
}

} // namespace

TEST(Runtime, BundleTransferRelightsToTheHandComputedDotProduct) {
    // Two vertices at order 2: transfer[v][j][c] = (v + 1) * (j + 1) * (c + 1) / 10, lighting[j][c] = j - c.
    // Vertex 0, channel c: sum_j (j + 1)(c + 1)(j - c) / 10.
    std::vector<float> transfer(2 * 4 * 3), lighting(4 * 3);
    for (int v = 0; v < 2; ++v)
        for (int j = 0; j < 4; ++j)
            for (int c = 0; c < 3; ++c) transfer[(v * 4 + j) * 3 + c] = float((v + 1) * (j + 1) * (c + 1)) / 10.0f;
    for (int j = 0; j < 4; ++j)
        for (int c = 0; c < 3; ++c) lighting[j * 3 + c] = float(j - c);
    std::vector<float> positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    ScratchDir scratch;
    fs::path path = scratch.path / "dot.glb";
    std::vector<float> threeRows = transfer;
    threeRows.resize(3 * 4 * 3, 0.0f); // the triangle's third vertex has no transfer
    prt::writeBundle(path.string(), transferBundle(positions, 2, threeRows));

    prt::RelightModel model = prt::loadRelightModel(path.string());
    ASSERT_EQ(model.vertexCount, 3u);
    ASSERT_EQ(model.order, 2);
    std::vector<float> radiance(3 * 3);
    prt::relight(model, lighting.data(), 0, 3, radiance.data());
    // channel 0: (1*0 + 2*1 + 3*2 + 4*3) / 10 = 2; channel 1: 2 * (1*-1 + 0 + 3*1 + 4*2) / 10 = 2;
    // channel 2: 3 * (1*-2 + 2*-1 + 0 + 4*1) / 10 = 0. Vertex 1 doubles them.
    const float expected[9] = {2.0f, 2.0f, 0.0f, 4.0f, 4.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    for (int i = 0; i < 9; ++i) EXPECT_NEAR(radiance[i], expected[i], 1e-5f) << i;
}

TEST(Runtime, KernelMatchesDoublePrecisionAtEveryOrder) {
    // Orders 3..8 take the unrolled paths, 1, 2 and 9 the generic one.
    for (int order = 1; order <= 9; ++order) {
        prt::RelightModel model = randomModel(257, order, 7 + order);
        std::vector<float> lighting = randomValues(size_t(order) * order * 3, 100 + order);
        std::vector<float> radiance(size_t(model.vertexCount) * 3);
        prt::relight(model.transfer.data(), model.vertexCount, order * order, lighting.data(), radiance.data());
        std::vector<double> expected = referenceRadiance(model, lighting.data());
        for (size_t i = 0; i < radiance.size(); ++i)
            ASSERT_NEAR(radiance[i], expected[i], 1e-5 * order * order) << "order " << order << " value " << i;
    }
}

// The kernel's documented order of additions (relight.cpp): lane i of 12 sums values i, i + 12, i + 24, ... of the
// row, from +0, each product rounded and then added; lanes 0..5 add lanes 6..11; channel c is lane c + lane c + 3.
// Written out in scalars, with nothing shared with the kernel.
void laneOrderRadiance(const float* row, int values, const float* lighting, float* radiance) {
    float lane[12] = {};
    for (int k = 0; k < values; ++k) lane[k % 12] += row[k] * lighting[k];
    for (int i = 0; i < 6; ++i) lane[i] += lane[i + 6];
    for (int c = 0; c < 3; ++c) radiance[c] = lane[c] + lane[c + 3];
}

// `count` floats that end where an unreadable page begins, so that a read past the last one faults, in any build.
struct GuardedFloats {
    size_t count, mappedBytes;
    void* mapping;
    float* data;
    explicit GuardedFloats(size_t n) : count(n) {
        const size_t page = size_t(sysconf(_SC_PAGESIZE)), bytes = (n * sizeof(float) + page - 1) / page * page;
        mappedBytes = bytes + page;
        mapping = mmap(nullptr, mappedBytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        if (mapping == MAP_FAILED) throw std::runtime_error("mmap failed");
        char* guard = static_cast<char*>(mapping) + bytes;
        if (mprotect(guard, page, PROT_NONE) != 0) throw std::runtime_error("mprotect failed");
        data = reinterpret_cast<float*>(guard) - n;
    }
    ~GuardedFloats() { munmap(mapping, mappedBytes); }
    GuardedFloats(const GuardedFloats&) = delete;
    GuardedFloats& operator=(const GuardedFloats&) = delete;
};

// Orders 1..5 take the vector kernel where the processor has AVX2 (relight_vector.cpp; orders 3 and 5 leave the
// last row to the lane loop), 6 and more the lane loop: every order gives the documented order's bits. The transfer
// ends at an unreadable page (so a read past its last row faults), a third of its values +-0 against
// lighting with exact zeros (so -0 products reach every lane), and every 7th row starts with NaN or infinity: an odd
// order's 4-value tail load reads that value for the row before, whose masked fourth product must leave it finite.
TEST(Runtime, KernelGivesTheDocumentedOrderOfAdditionsBitForBitAtEveryOrder) {
    for (int order = 1; order <= 9; ++order) {
        SCOPED_TRACE("order " + std::to_string(order));
        const int values = order * order * 3;
        for (size_t vertexCount : {size_t(1), size_t(2), size_t(3), size_t(4099)}) {
            std::mt19937 random(uint32_t(order * 31 + vertexCount));
            std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
            GuardedFloats guarded(vertexCount * values);
            std::span<float> transfer(guarded.data, guarded.count);
            for (float& value : transfer) value = random() % 3 == 0 ? (random() % 2 ? -0.0f : 0.0f) : uniform(random);
            for (size_t v = 0; v < vertexCount; v += 7)
                transfer[v * values] = v % 2 ? std::numeric_limits<float>::infinity() : std::nanf("");
            std::vector<float> lighting = randomValues(size_t(values), uint32_t(order + 60));
            for (int i = 0; i < values; i += 5) lighting[i] = i % 2 ? -0.0f : 0.0f;
            lighting[0] = 0.5f; // the NaN and infinity rows' own first product stays NaN or infinite

            std::vector<float> radiance(vertexCount * 3);
            prt::relight(transfer.data(), vertexCount, order * order, lighting.data(), radiance.data());
            size_t compared = 0;
            for (size_t v = 0; v < vertexCount; ++v) {
                float expected[3];
                laneOrderRadiance(transfer.data() + v * values, values, lighting.data(), expected);
                for (int c = 0; c < 3; ++c) {
                    const float got = radiance[v * 3 + c];
                    if (std::isnan(expected[c])) {
                        ASSERT_TRUE(std::isnan(got)) << "vertex " << v << " channel " << c;
                        continue;
                    }
                    ASSERT_EQ(std::memcmp(&got, &expected[c], sizeof got), 0)
                        << "vertex " << v << " of " << vertexCount << " channel " << c << ": " << got << " for "
                        << expected[c];
                    ++compared;
                }
            }
            EXPECT_GT(compared, vertexCount * 3 / 2) << "most values are finite";
        }
    }
}

TEST(Runtime, RangeEqualsTheSliceOfTheFullResult) {
    prt::RelightModel model = randomModel(10007, 5, 3);
    std::vector<float> lighting = randomValues(25 * 3, 4);
    std::vector<float> full(size_t(model.vertexCount) * 3);
    prt::relight(model, lighting.data(), 0, model.vertexCount, full.data());

    const size_t begin = 4093, end = 9001;
    std::vector<float> part((end - begin) * 3);
    prt::relight(model, lighting.data(), begin, end, part.data());
    for (size_t i = 0; i < part.size(); ++i) ASSERT_EQ(part[i], full[begin * 3 + i]) << i;

    // The kernel on an offset pointer is the same range, single-threaded.
    std::vector<float> kernel((end - begin) * 3);
    prt::relight(model.transfer.data() + begin * 25 * 3, end - begin, 25, lighting.data(), kernel.data());
    EXPECT_EQ(kernel, part);

    EXPECT_THROW(prt::relight(model, lighting.data(), 10, model.vertexCount + 1, full.data()), prt::Error);
}

TEST(Runtime, LightingOfAnotherOrderUsesTheCommonPrefix) {
    prt::RelightModel model = randomModel(64, 3, 11);
    std::vector<float> lighting5 = randomValues(25 * 3, 12);
    std::vector<float> fitted = prt::fitLighting(lighting5.data(), 25, 9);
    ASSERT_EQ(fitted.size(), 27u);
    EXPECT_TRUE(std::equal(fitted.begin(), fitted.end(), lighting5.begin()));

    std::vector<float> padded = prt::fitLighting(lighting5.data(), 4, 9);
    for (int i = 0; i < 27; ++i) EXPECT_EQ(padded[i], i < 12 ? lighting5[i] : 0.0f) << i;
    // Relighting with padded lighting ignores the transfer beyond band 1.
    prt::RelightModel band1 = randomModel(64, 2, 0);
    for (size_t v = 0; v < 64; ++v)
        std::copy_n(&model.transfer[v * 27], 12, &band1.transfer[v * 12]);
    std::vector<float> a(64 * 3), b(64 * 3);
    prt::relight(model, padded.data(), 0, 64, a.data());
    prt::relight(band1, lighting5.data(), 0, 64, b.data());
    for (size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a[i], b[i], 1e-6f) << i;
}

TEST(Runtime, FullTurnIsTheIdentity) {
    std::vector<float> lighting = randomValues(64 * 3, 5);
    double R[9];
    prt::sh::rotationY(360.0, R);
    std::vector<float> turned = prt::rotateLighting(lighting.data(), 8, R);
    for (size_t i = 0; i < lighting.size(); ++i) EXPECT_NEAR(turned[i], lighting[i], 1e-5f) << i;
}

TEST(Runtime, RotatingCoefficientsEqualsRotatingTheEnvironment) {
    // Turning an equirect map a quarter turn about +Y moves whole columns, and the pixel grid (with its solid
    // angles) maps onto itself, so projection and rotation commute exactly: only float rounding separates them.
    prt::EnvironmentMap env = lobeEnvironment(128);
    double R[9];
    prt::sh::rotationY(90.0, R);
    prt::EnvironmentMap turnedEnv = rotateInPixels(env, R);
    ASSERT_NE(turnedEnv.radiance.rgb, env.radiance.rgb);

    const int order = 6;
    std::vector<float> rotatedCoefficients = prt::environmentLighting(env, order, R, prt::sh::Window::None);
    std::vector<float> projectedTurned = prt::environmentLighting(turnedEnv, order, nullptr, prt::sh::Window::None);
    double scale = maxAbs(projectedTurned);
    for (size_t i = 0; i < projectedTurned.size(); ++i)
        EXPECT_NEAR(rotatedCoefficients[i], projectedTurned[i], 2e-5 * scale) << i;
    // The lobe is off-axis, so the turn really changed the coefficients.
    std::vector<float> unturned = prt::environmentLighting(env, order, nullptr, prt::sh::Window::None);
    EXPECT_GT(std::fabs(unturned[3 * 3] - projectedTurned[3 * 3]), 0.1 * scale);

    // And through the kernel.
    prt::RelightModel model = randomModel(100, order, 9);
    std::vector<float> a(300), b(300);
    prt::relight(model, rotatedCoefficients.data(), 0, 100, a.data());
    prt::relight(model, projectedTurned.data(), 0, 100, b.data());
    for (size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a[i], b[i], 1e-4 * scale) << i;
}

TEST(Runtime, WhiteFurnace) {
    // Unoccluded white Lambertian sphere: transfer[v][lm] = A_l Y_lm(n) / pi. Constant radiance L in, L out.
    const int order = 5, n = order * order;
    const uint32_t vertexCount = 200;
    std::vector<float> positions(vertexCount * 3), transfer(size_t(vertexCount) * n * 3);
    for (uint32_t v = 0; v < vertexCount; ++v) {
        // Fibonacci sphere: directions spread over all of S^2.
        double z = 1.0 - (2.0 * v + 1.0) / vertexCount, r = std::sqrt(1.0 - z * z);
        double phi = v * std::numbers::pi * (3.0 - std::sqrt(5.0));
        double normal[3] = {r * std::cos(phi), r * std::sin(phi), z};
        double basis[64];
        prt::sh::evaluate(order, normal[0], normal[1], normal[2], basis);
        for (int c = 0; c < 3; ++c) positions[v * 3 + c] = float(normal[c]);
        for (int l = 0; l < order; ++l)
            for (int m = -l; m <= l; ++m)
                for (int c = 0; c < 3; ++c)
                    transfer[(size_t(v) * n + prt::sh::index(l, m)) * 3 + c] =
                        float(prt::sh::clampedCosine(l) * basis[prt::sh::index(l, m)] / std::numbers::pi);
    }
    ScratchDir scratch;
    fs::path path = scratch.path / "furnace.glb";
    prt::writeBundle(path.string(), transferBundle(positions, order, transfer));
    prt::RelightModel model = prt::loadRelightModel(path.string());

    const float L[3] = {0.5f, 1.0f, 2.0f};
    // Constant radiance as SH: only Y_00 = 1 / sqrt(4 pi), so coefficient 0 is L sqrt(4 pi). Exact up to rounding.
    std::vector<float> lighting(n * 3, 0.0f);
    for (int c = 0; c < 3; ++c) lighting[c] = float(L[c] * 2.0 * std::sqrt(std::numbers::pi));
    std::vector<float> radiance(vertexCount * 3);
    prt::relight(model, lighting.data(), 0, vertexCount, radiance.data());
    for (uint32_t v = 0; v < vertexCount; ++v)
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(radiance[v * 3 + c], L[c], 1e-6 * L[c]) << v << " " << c;

    // The same through a constant environment map. Its texel solid angles are exact, but sampling each row at
    // its centre is the midpoint rule in the polar angle, off by O((pi / H)^2) for the higher bands.
    prt::EnvironmentMap env;
    env.radiance.width = 128;
    env.radiance.height = 64;
    for (int i = 0; i < 128 * 64; ++i) env.radiance.rgb.insert(env.radiance.rgb.end(), L, L + 3);
    lighting = prt::environmentLighting(env, order, nullptr, prt::sh::Window::None);
    prt::relight(model, lighting.data(), 0, vertexCount, radiance.data());
    const double quadrature = std::pow(std::numbers::pi / 64, 2);
    for (uint32_t v = 0; v < vertexCount; ++v)
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(radiance[v * 3 + c], L[c], quadrature * L[c]) << v << " " << c;
}

// A bundle as the relight stage reads it: the transfer (float16 here) and the albedo it excludes, with their values,
// and the other layers (a bounce layer; an integer layer) described but empty; the model is readBundle's bit for
// bit. Without a transfer layer every layer has readBundle's values. A corrupted byte in a layer it skips is still
// refused: the whole file is checked.
TEST(Runtime, RelightReadsOnlyTheLayersItUsesAndChecksTheWholeFile) {
    const std::vector<float> positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    prt::Bundle bundle = transferBundle(positions, 3, randomValues(3 * 9 * 3, 7));
    bundle.layers[0].componentType = "float16";
    bundle.layers[0].params["albedo"] = "excluded";
    prt::Layer albedo;
    albedo.name = "diffuse_albedo";
    albedo.domain = "vertex";
    albedo.semantic = "diffuse_albedo_rgb";
    albedo.shape = {3, 3};
    albedo.data = {0.25f, 0.5f, 0.75f, 1.0f, 0.0f, 0.5f, 0.125f, 0.25f, 0.375f};
    prt::Layer bounce = bundle.layers[0];
    bounce.name = "transfer_bounce";
    bounce.componentType = "float32";
    bounce.data = randomValues(3 * 9 * 3, 8);
    prt::Layer codes;
    codes.name = "labels";
    codes.domain = "vertex";
    codes.semantic = "label";
    codes.shape = {3};
    codes.componentType = "uint8";
    codes.integers = {1, 2, 3};
    bundle.layers.insert(bundle.layers.begin(), bounce); // before the transfer: the kept layers are not the first
    bundle.layers.push_back(albedo);
    bundle.layers.push_back(codes);
    ScratchDir scratch;
    const std::string path = (scratch.path / "scene.glb").string();
    prt::writeBundle(path, bundle);

    const prt::Bundle read = prt::readRelightBundle(path);
    ASSERT_EQ(read.layers.size(), 4u);
    for (const prt::Layer& layer : read.layers) {
        const bool kept = layer.name == "transfer" || layer.name == "diffuse_albedo";
        EXPECT_EQ(layer.data.size(), kept ? (layer.name == "transfer" ? 81u : 9u) : 0u) << layer.name;
        EXPECT_TRUE(layer.integers.empty()) << layer.name;
    }
    const prt::RelightModel model = prt::loadRelightModel(path);
    const prt::RelightModel whole = prt::relightModel(prt::readBundle(path), path);
    EXPECT_EQ(model.order, 3);
    EXPECT_TRUE(model.albedoExcluded);
    EXPECT_EQ(0, std::memcmp(model.transfer.data(), whole.transfer.data(), 81 * sizeof(float)));
    EXPECT_EQ(model.albedo, whole.albedo);
    EXPECT_EQ(model.albedo, albedo.data);

    // Without a "transfer" layer (an adaptive bundle's case) every layer comes with readBundle's values.
    prt::Bundle noTransfer = bundle;
    noTransfer.layers.erase(noTransfer.layers.begin() + 1);
    const std::string other = (scratch.path / "other.glb").string();
    prt::writeBundle(other, noTransfer);
    const prt::Bundle all = prt::readRelightBundle(other), expected = prt::readBundle(other);
    ASSERT_EQ(all.layers.size(), 3u);
    for (size_t i = 0; i < all.layers.size(); ++i) {
        EXPECT_EQ(all.layers[i].data, expected.layers[i].data) << all.layers[i].name;
        EXPECT_EQ(all.layers[i].integers, expected.layers[i].integers) << all.layers[i].name;
    }
    EXPECT_EQ(all.layers[2].integers, (std::vector<uint32_t>{1, 2, 3}));

    // One bit of the bounce layer's first value, a layer readRelightBundle does not keep.
    std::string bytes = prt::readFileBytes(path);
    float first = bounce.data[0];
    const size_t at = bytes.find(std::string(reinterpret_cast<const char*>(&first), 4));
    ASSERT_NE(at, std::string::npos);
    bytes[at] ^= 0x01;
    prt::writeBytesAtomic(path, bytes);
    try {
        prt::loadRelightModel(path);
        FAIL() << "a corrupted bundle was read";
    } catch (const prt::Error& error) {
        EXPECT_NE(std::string(error.what()).find(path), std::string::npos) << error.what();
    }
}

TEST(Runtime, BundleWithoutTransferIsAnErrorNamingTheFile) {
    prt::Bundle bundle = transferBundle({0, 0, 0, 1, 0, 0, 0, 1, 0}, 2, std::vector<float>(36, 0.5f));
    bundle.layers[0].name = "visibility";
    ScratchDir scratch;
    fs::path path = scratch.path / "no_transfer.glb";
    prt::writeBundle(path.string(), bundle);
    try {
        prt::loadRelightModel(path.string());
        FAIL() << "no error";
    } catch (const prt::Error& e) {
        EXPECT_EQ(e.file(), path.string());
        EXPECT_NE(e.problem().find("transfer"), std::string::npos) << e.what();
        EXPECT_EQ(e.exitCode(), prt::kExitInput);
    }
}

TEST(Runtime, MalformedTransferLayersAreErrors) {
    auto expectError = [](prt::Bundle bundle, const char* what) {
        try {
            prt::relightModel(std::move(bundle), "x.glb");
            ADD_FAILURE() << "no error for " << what;
        } catch (const prt::Error& e) {
            EXPECT_EQ(e.file(), "x.glb") << what;
            EXPECT_EQ(e.place().rfind("layer \"transfer\"", 0), 0u) << what;
        }
    };
    const std::vector<float> positions = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    prt::Bundle good = transferBundle(positions, 2, std::vector<float>(36, 0.5f));
    EXPECT_EQ(prt::relightModel(good, "x.glb").order, 2);

    prt::Bundle bundle = good;
    bundle.layers[0].shape = {3, 5, 3};
    bundle.layers[0].data.resize(45);
    expectError(bundle, "5 coefficients");
    bundle = good;
    bundle.layers[0].params["order"] = 3;
    expectError(bundle, "params.order");
    bundle = good;
    bundle.layers[0].semantic = "sh_transfer_gray";
    expectError(bundle, "semantic");
    bundle = good;
    bundle.mesh.positions.resize(12);
    expectError(bundle, "row count");
    bundle = good;
    bundle.layers[0].data[7] = NAN;
    expectError(bundle, "NaN");
}

TEST(Runtime, ReadsPrtShJson) {
    ScratchDir scratch;
    const fs::path& dir = scratch.path;
    std::ofstream(dir / "good.json") << R"({"format":"prt-sh","order":2,"coefficients":[[1,2,3],[4,5,6],[7,8,9],[0,0,0.5]]})";
    int order = 0;
    std::vector<float> lighting = prt::readLightingJson((dir / "good.json").string(), &order);
    EXPECT_EQ(order, 2);
    EXPECT_EQ(lighting, (std::vector<float>{1, 2, 3, 4, 5, 6, 7, 8, 9, 0, 0, 0.5f}));

    const char* bad[] = {
        R"({"format":"prt-sh","order":2,"coefficients":[[1,2,3]]})",
        R"({"format":"other","order":1,"coefficients":[[1,2,3]]})",
        R"({"format":"prt-sh","order":1,"coefficients":[[1,2]]})",
        R"({"format":"prt-sh","order":1,"coefficients":[[1,2,1e99]]})",
        R"({"format":"prt-sh","order":0,"coefficients":[]})",
        R"({"format":"prt-sh", )",
    };
    for (const char* text : bad) {
        std::ofstream(dir / "bad.json") << text;
        EXPECT_THROW(prt::readLightingJson((dir / "bad.json").string(), &order), prt::Error) << text;
    }
}
