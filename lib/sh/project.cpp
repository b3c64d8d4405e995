// Projection of environment radiance onto SH with exact texel solid angles, and irradiance from SH.
#include "sh.h"

#include "core.h"

#include <algorithm>
#include <atomic>
#include <thread>
#include <cmath>
#include <numbers>

namespace prt::sh {

namespace {

void texelDirection(const EnvironmentMap& env, int x, int y, double d[3]) {
    if (env.layout == EnvLayout::Equirectangular)
        equirectDirection(env.radiance.width, env.radiance.height, x, y, d);
    else
        cubeStripDirection(env.radiance.width, x, y, d);
}

void checkEnvironment(const EnvironmentMap& env, const char* place) {
    const Image& image = env.radiance;
    bool shaped = env.layout == EnvLayout::Equirectangular ? image.width == 2 * image.height
                                                            : image.height == 6 * image.width;
    if (image.width <= 0 || !shaped || image.rgb.size() != size_t(image.width) * image.height * 3)
        throw Error("", place, "environment image size does not match its layout", kExitFailure);
}

} // namespace

void equirectDirection(int width, int height, double x, double y, double d[3]) {
    double theta = std::numbers::pi * (y + 0.5) / height;
    double phi = 2.0 * std::numbers::pi * (x + 0.5) / width - std::numbers::pi;
    d[0] = std::sin(theta) * std::sin(phi);
    d[1] = std::cos(theta);
    d[2] = -std::sin(theta) * std::cos(phi);
}

void cubeStripDirection(int faceSize, double x, double y, double d[3]) {
    int face = std::clamp(int(std::floor((y + 0.5) / faceSize)), 0, 5); // texel y spans y - 0.5 .. y + 0.5
    double a = 2.0 * (x + 0.5) / faceSize - 1.0;
    double b = 1.0 - 2.0 * (y - face * faceSize + 0.5) / faceSize;
    cubeFaceDirection(face, a, b, d);
}

std::vector<double> texelSolidAngles(const EnvironmentMap& env) {
    checkEnvironment(env, "sh::texelSolidAngles");
    int width = env.radiance.width, height = env.radiance.height;
    std::vector<double> solidAngle(size_t(width) * height);
    if (env.layout == EnvLayout::Equirectangular) {
        for (int y = 0; y < height; ++y) {
            double row = 2.0 * std::numbers::pi / width *
                         (std::cos(std::numbers::pi * y / height) - std::cos(std::numbers::pi * (y + 1) / height));
            std::fill_n(&solidAngle[size_t(y) * width], width, row);
        }
        return solidAngle;
    }
    // Every face has the same texel solid angles; a texel's is the signed corner sum over its rectangle.
    int size = width;
    for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
            double a0 = 2.0 * x / size - 1.0, a1 = 2.0 * (x + 1) / size - 1.0;
            double b0 = 2.0 * y / size - 1.0, b1 = 2.0 * (y + 1) / size - 1.0;
            double omega = cubeRectangleSolidAngle(a0, a1, b0, b1);
            for (int face = 0; face < 6; ++face) solidAngle[(size_t(face) * size + y) * size + x] = omega;
        }
    return solidAngle;
}

std::vector<float> projectEnvironment(const EnvironmentMap& env, int order, int threads) {
    if (order < 1 || order > kMaxOrder)
        throw Error("", "sh::projectEnvironment",
                    "order " + std::to_string(order) + " outside 1.." + std::to_string(kMaxOrder), kExitFailure);
    std::vector<double> solidAngle = texelSolidAngles(env);
    const Image& image = env.radiance;
    int width = image.width, height = image.height, count = coefficientCount(order);

    // Fixed row blocks, each summed in its own double buffer and reduced in block order: the result does not
    // depend on which thread takes which block, so it is bit-identical for any thread count.
    constexpr int kRowsPerBlock = 8;
    int blockCount = (height + kRowsPerBlock - 1) / kRowsPerBlock;
    std::vector<double> partial(size_t(blockCount) * count * 3, 0.0);
    Progress progress("project environment", uint64_t(height));
    // std::threads taking the next block in turn (no TBB: the thin runtime projects too).
    std::atomic<int> nextBlock{0};
    auto projectBlocks = [&] {
        std::vector<double> basis(count);
        for (int block; (block = nextBlock.fetch_add(1)) < blockCount;) {
            double* sum = &partial[size_t(block) * count * 3];
            int yEnd = std::min(height, (block + 1) * kRowsPerBlock);
            for (int y = block * kRowsPerBlock; y < yEnd; ++y) {
                for (int x = 0; x < width; ++x) {
                    size_t texel = size_t(y) * width + x;
                    double d[3];
                    texelDirection(env, x, y, d);
                    evaluate(order, d[0], d[1], d[2], basis.data());
                    const float* radiance = &image.rgb[texel * 3];
                    double r = radiance[0] * solidAngle[texel], g = radiance[1] * solidAngle[texel],
                           b = radiance[2] * solidAngle[texel];
                    for (int i = 0; i < count; ++i) {
                        sum[i * 3 + 0] += basis[i] * r;
                        sum[i * 3 + 1] += basis[i] * g;
                        sum[i * 3 + 2] += basis[i] * b;
                    }
                }
            }
            progress.add(uint64_t(yEnd - block * kRowsPerBlock));
        }
    };
    int workers = std::clamp(threads > 0 ? threads : int(std::thread::hardware_concurrency()), 1, blockCount);
    std::vector<std::thread> pool;
    for (int i = 1; i < workers; ++i) pool.emplace_back(projectBlocks);
    projectBlocks();
    for (std::thread& thread : pool) thread.join();
    progress.finish();

    std::vector<double> total(size_t(count) * 3, 0.0);
    for (int block = 0; block < blockCount; ++block)
        for (size_t i = 0; i < total.size(); ++i) total[i] += partial[size_t(block) * count * 3 + i];
    return std::vector<float>(total.begin(), total.end());
}

void irradiance(int order, const float* radianceCoeffs, const double n[3], double out[3]) {
    std::vector<double> basis(coefficientCount(order));
    evaluate(order, n[0], n[1], n[2], basis.data());
    out[0] = out[1] = out[2] = 0.0;
    for (int l = 0; l < order; ++l) {
        double a = clampedCosine(l);
        for (int i = l * l; i < (l + 1) * (l + 1); ++i)
            for (int c = 0; c < 3; ++c) out[c] += a * basis[i] * radianceCoeffs[i * 3 + c];
    }
}

} // namespace prt::sh
