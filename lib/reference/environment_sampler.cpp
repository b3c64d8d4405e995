// Luminance importance sampling of an environment map, and the nearest-texel lookup it is consistent with.
#include "path_tracer.h"

#include "core.h"
#include "luminance.h"
#include "sh.h"

#include <OpenEXR/ImfEnvmap.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace prt::pathtrace {

namespace {

// A unit direction's distance scale onto the cube: d / max|d_i| lies on the cube [-1, 1]^3, and the solid angle
// of face-plane area dA there is dA / r^3 with r = 1 / max|d_i|.
float cubeDistanceCubed(const float d[3]) {
    float major = std::max({std::abs(d[0]), std::abs(d[1]), std::abs(d[2])});
    return 1.0f / (major * major * major);
}

size_t equirectTexel(int width, int height, const float d[3]) {
    double theta = std::acos(std::clamp(double(d[1]), -1.0, 1.0));
    double phi = std::atan2(double(d[0]), -double(d[2]));
    int x = int(std::floor((phi + std::numbers::pi) / (2.0 * std::numbers::pi) * width));
    int y = int(std::floor(theta / std::numbers::pi * height));
    return size_t(std::clamp(y, 0, height - 1)) * width + size_t(std::clamp(x, 0, width - 1));
}

size_t cubeStripTexel(int faceSize, const float d[3]) {
    // OpenEXR's ImfEnvmap.h defines the layout (docs/conventions.md). It places texel centres on the face edges,
    // (faceSize - 1) apart; here texels tile each face edge to edge, so its in-face position is stretched.
    Imath::Box2i window(Imath::V2i(0, 0), Imath::V2i(faceSize - 1, 6 * faceSize - 1));
    Imf::CubeMapFace face;
    Imath::V2f inFace;
    Imf::CubeMap::faceAndPixelPosition(Imath::V3f(d[0], d[1], d[2]), window, face, inFace);
    float stretch = faceSize > 1 ? float(faceSize) / float(faceSize - 1) : 0.0f;
    int column = std::clamp(int(inFace.x * stretch), 0, faceSize - 1);
    int row = std::clamp(int(inFace.y * stretch), 0, faceSize - 1);
    Imath::V2f pixel = Imf::CubeMap::pixelPosition(face, window, Imath::V2f(float(column), float(row)));
    return size_t(std::lround(pixel.y)) * faceSize + size_t(std::lround(pixel.x));
}

} // namespace

EnvironmentSampler makeEnvironmentSampler(const EnvironmentMap& env) {
    EnvironmentSampler sampler;
    sampler.layout = env.layout;
    sampler.width = env.radiance.width;
    sampler.height = env.radiance.height;
    std::vector<double> solidAngle = sh::texelSolidAngles(env); // checks the size against the layout
    size_t width = size_t(sampler.width), height = size_t(sampler.height);

    // Texel weights, running within each row; a row's total is its marginal weight.
    std::vector<double> weight(width * height);
    sampler.texels.resize(width * height);
    sampler.columnCdf.resize(width * height);
    sampler.rowCdf.resize(height);
    double total = 0.0;
    for (size_t y = 0; y < height; ++y) {
        double row = 0.0;
        for (size_t x = 0; x < width; ++x) {
            size_t i = y * width + x;
            const float* rgb = &env.radiance.rgb[i * 3];
            std::copy(rgb, rgb + 3, sampler.texels[i].radiance);
            // |radiance| per channel: the same luminance for the maps read from files (never negative), and a
            // valid density for signed radiance (prt reference --lights), whose estimate keeps the sign.
            weight[i] = (kLuminance[0] * std::abs(rgb[0]) + kLuminance[1] * std::abs(rgb[1]) +
                         kLuminance[2] * std::abs(rgb[2])) *
                        solidAngle[i];
            row += weight[i];
            sampler.columnCdf[i] = row;
        }
        // A black row is never chosen, so its conditional distribution is never read.
        if (row > 0.0)
            for (size_t x = 0; x < width; ++x) sampler.columnCdf[y * width + x] /= row;
        total += row;
        sampler.rowCdf[y] = total;
    }

    if (total <= 0.0) {
        sampler.rowCdf.clear();
        return sampler;
    }
    for (double& c : sampler.rowCdf) c /= total;

    // Within a texel, equirect directions are uniform in solid angle and cube-strip directions uniform in face
    // area; the density stored is the texel's probability over that measure.
    double faceTexelArea = env.layout == EnvLayout::CubeStrip ? std::pow(2.0 / double(width), 2) : 0.0;
    for (size_t i = 0; i < width * height; ++i) {
        double measure = env.layout == EnvLayout::CubeStrip ? faceTexelArea : solidAngle[i];
        sampler.texels[i].density = float(weight[i] / total / measure);
    }
    if (env.layout == EnvLayout::Equirectangular) {
        sampler.rowCosine.resize(height + 1);
        for (size_t y = 0; y <= height; ++y)
            sampler.rowCosine[y] = std::cos(std::numbers::pi * double(y) / double(height));
    }
    return sampler;
}

size_t environmentTexel(const EnvironmentSampler& sampler, const float d[3]) {
    return sampler.layout == EnvLayout::Equirectangular ? equirectTexel(sampler.width, sampler.height, d)
                                                        : cubeStripTexel(sampler.width, d);
}

float environmentPdf(const EnvironmentSampler& sampler, size_t texel, const float d[3]) {
    if (sampler.rowCdf.empty()) return 0.0f;
    float density = sampler.texels[texel].density;
    return sampler.layout == EnvLayout::Equirectangular ? density : density * cubeDistanceCubed(d);
}

EnvironmentSample sampleEnvironment(const EnvironmentSampler& sampler, double uRow, double uColumn, float u1,
                                    float u2) {
    // Zero-weight rows and texels own empty cdf intervals, so upper_bound never lands on one. The last non-black
    // row's and texel's running sums are the totals themselves, so their cdf is exactly 1 > u.
    size_t width = size_t(sampler.width);
    int y = int(std::upper_bound(sampler.rowCdf.begin(), sampler.rowCdf.end(), uRow) - sampler.rowCdf.begin());
    const double* row = &sampler.columnCdf[size_t(y) * width];
    int x = int(std::upper_bound(row, row + width, uColumn) - row);

    double d[3];
    if (sampler.layout == EnvLayout::Equirectangular) {
        double phi = 2.0 * std::numbers::pi * (x + u1) / sampler.width - std::numbers::pi;
        double cosTheta = sampler.rowCosine[y] + u2 * (sampler.rowCosine[y + 1] - sampler.rowCosine[y]);
        double sinTheta = std::sqrt(std::max(0.0, 1.0 - cosTheta * cosTheta));
        d[0] = sinTheta * std::sin(phi);
        d[1] = cosTheta;
        d[2] = -sinTheta * std::cos(phi);
    } else {
        sh::cubeStripDirection(sampler.width, x + u1 - 0.5, y + u2 - 0.5, d);
    }
    EnvironmentSample sample;
    sample.texel = size_t(y) * width + size_t(x);
    for (int c = 0; c < 3; ++c) sample.direction[c] = float(d[c]);
    sample.pdf = environmentPdf(sampler, sample.texel, sample.direction);
    return sample;
}

} // namespace prt::pathtrace
