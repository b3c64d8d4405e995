// prt render --background: the environment map behind the picture, where the primary ray escapes.
#include "render.h"

#include "core.h"
#include "sh.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace prt {

namespace {

// Radiance of an equirectangular map (docs/conventions.md) along unit direction e, bilinear between texel centres:
// u repeats, v clamps at the poles. The formula of viewer/sky.js, in double.
void equirectBilinear(const Image& map, const double e[3], float out[3]) {
    const double pi = std::numbers::pi;
    const double theta = std::acos(std::clamp(e[1], -1.0, 1.0)), phi = std::atan2(e[0], -e[2]);
    const double u = (phi + pi) / (2.0 * pi) * map.width - 0.5, v = theta / pi * map.height - 0.5;
    const double x0 = std::floor(u), y0 = std::floor(v), fu = u - x0, fv = v - y0;
    auto texel = [&](double x, double y, int c) {
        int ix = int(x) % map.width;
        if (ix < 0) ix += map.width;
        int iy = std::clamp(int(y), 0, map.height - 1);
        return double(map.rgb[(size_t(iy) * map.width + ix) * 3 + c]);
    };
    for (int c = 0; c < 3; ++c)
        out[c] = float((1.0 - fv) * ((1.0 - fu) * texel(x0, y0, c) + fu * texel(x0 + 1, y0, c)) +
                       fv * ((1.0 - fu) * texel(x0, y0 + 1, c) + fu * texel(x0 + 1, y0 + 1, c)));
}

} // namespace

void drawEnvironmentBackground(RenderedImage& image, const EnvironmentMap& environment, const std::string& envSource,
                               const PinholeCamera& camera, double rotateYDegrees) {
    if (environment.layout != EnvLayout::Equirectangular)
        throw Error(envSource, "--background", "the background needs an equirectangular (2:1) map", kExitUsage);
    const Image& map = environment.radiance;
    if (map.width < 1 || map.height < 1 || map.rgb.size() != size_t(map.width) * map.height * 3)
        throw Error(envSource, "--background", "the map has no texels or a wrong size");
    const size_t pixels = size_t(camera.width) * camera.height;
    if (image.radiance.width != camera.width || image.radiance.height != camera.height ||
        image.radiance.rgb.size() != pixels * 3 || image.coverage.size() != pixels)
        throw Error("", "render", "the picture and the camera differ in size", kExitFailure);
    const PinholeRays rays = pinholeRays(camera);
    double R[9];
    sh::rotationY(rotateYDegrees, R);
    for (size_t pixel = 0; pixel < pixels; ++pixel) {
        if (image.coverage[pixel] != 0.0f) continue;
        float d[3];
        pinholeRayDirection(rays, pixel, d);
        // The lighting turned by R shows the map at R^T d.
        double e[3];
        for (int r = 0; r < 3; ++r) e[r] = R[r] * d[0] + R[3 + r] * d[1] + R[6 + r] * d[2];
        equirectBilinear(map, e, &image.radiance.rgb[pixel * 3]);
    }
}

} // namespace prt
