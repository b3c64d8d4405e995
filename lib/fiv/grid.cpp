// The spherical sample grid around an occluder: dimensions, shell radii, directions, the bounding sphere.
#include "fiv.h"

#include "core.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace prt::fiv {

void checkGrid(const GridSpec& grid, const std::string& source, int exitCode) {
    auto refuse = [&](const std::string& problem) { throw Error(source, "--grid", problem, exitCode); };
    if (grid.azimuth < 3 || grid.azimuth > kMaxAzimuth)
        refuse("azimuth count " + std::to_string(grid.azimuth) + " is outside 3.." + std::to_string(kMaxAzimuth));
    if (grid.polar < 2 || grid.polar > kMaxPolar)
        refuse("polar count " + std::to_string(grid.polar) + " is outside 2.." + std::to_string(kMaxPolar));
    if (grid.shells < 1 || grid.shells > kMaxShells)
        refuse("shell count " + std::to_string(grid.shells) + " is outside 1.." + std::to_string(kMaxShells));
    if (uint64_t(grid.azimuth) * grid.polar * grid.shells > kMaxSamples)
        refuse("more than " + std::to_string(kMaxSamples) + " samples");
    if (!(grid.shellMin > 0.0 && std::isfinite(grid.shellMin)) || !(grid.shellMax > grid.shellMin) ||
        !std::isfinite(grid.shellMax) || grid.shellMax > 1e4)
        throw Error(source, "--shells", "needs 0 < MIN < MAX <= 10000 (units of the bounding-sphere radius)", exitCode);
    if (grid.spacing != "log" && grid.spacing != "linear")
        throw Error(source, "--spacing", "\"" + grid.spacing + "\" is not log or linear", exitCode);
}

void checkWork(const GridSpec& grid, int cube, int supersample, const std::string& source, int exitCode) {
    const uint64_t limit = maxElements() > UINT64_MAX / 16 ? UINT64_MAX : 16 * maxElements();
    // Every factor is capped (checkGrid, kMaxCube, kMaxSupersample), so the product fits 64 bits.
    const uint64_t naive = uint64_t(std::max(grid.azimuth, 0)) * uint64_t(std::max(grid.polar, 0)) *
                           uint64_t(std::max(grid.shells, 0)) * 6 * uint64_t(std::clamp(cube, 0, kMaxCube)) *
                           uint64_t(std::clamp(cube, 0, kMaxCube)) * uint64_t(std::clamp(supersample, 0, kMaxSupersample)) *
                           uint64_t(std::clamp(supersample, 0, kMaxSupersample));
    if (naive > limit)
        throw Error(source, "--grid", "samples x 6 cube^2 x supersample^2 = " + std::to_string(naive) +
                                          " ray-texel pairs, above the limit of " + std::to_string(limit) +
                                          " (16 x PRT_MAX_ELEMENTS; it bounds the visibility's time and mask memory)",
                    exitCode);
}

std::vector<double> shellRadii(const GridSpec& grid) {
    std::vector<double> radii(size_t(grid.shells));
    for (int k = 0; k < grid.shells; ++k) {
        double t = grid.shells > 1 ? double(k) / double(grid.shells - 1) : 0.0;
        radii[size_t(k)] = grid.spacing == "log"
                               ? grid.shellMin * std::pow(grid.shellMax / grid.shellMin, t)
                               : grid.shellMin + t * (grid.shellMax - grid.shellMin);
    }
    return radii;
}

void gridDirection(const GridSpec& grid, int i, int j, double d[3]) {
    if (j == 0 || j == grid.polar - 1) {
        d[0] = 0.0, d[1] = j == 0 ? 1.0 : -1.0, d[2] = 0.0;
        return;
    }
    double theta = std::numbers::pi * double(j) / double(grid.polar - 1);
    double phi = 2.0 * std::numbers::pi * double(i) / double(grid.azimuth);
    d[0] = std::sin(theta) * std::sin(phi);
    d[1] = std::cos(theta);
    d[2] = -std::sin(theta) * std::cos(phi);
}

BoundingSphere boundingSphere(const TriMesh& mesh) {
    BoundingSphere sphere;
    if (mesh.positions.empty()) throw Error("", "occluder", "mesh is empty", kExitInput);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t v = 0; v < mesh.vertexCount(); ++v)
        for (int c = 0; c < 3; ++c) {
            lo[c] = std::min(lo[c], double(mesh.positions[3 * v + c]));
            hi[c] = std::max(hi[c], double(mesh.positions[3 * v + c]));
        }
    for (int c = 0; c < 3; ++c) sphere.centre[size_t(c)] = 0.5 * (lo[c] + hi[c]);
    double r2 = 0.0;
    for (size_t v = 0; v < mesh.vertexCount(); ++v) {
        double s = 0.0;
        for (int c = 0; c < 3; ++c) s += std::pow(double(mesh.positions[3 * v + c]) - sphere.centre[size_t(c)], 2);
        r2 = std::max(r2, s);
    }
    // A hair larger, so float positions on the sphere are inside it.
    sphere.radius = std::sqrt(r2) * (1.0 + 1e-6);
    return sphere;
}

nlohmann::json gridParams(const GridSpec& grid, const BoundingSphere& sphere) {
    return {{"resolution", {grid.shells, grid.polar, grid.azimuth}},
            {"axes", {"shell", "polar", "azimuth"}},
            {"azimuth", grid.azimuth},
            {"polar", grid.polar},
            {"shells", grid.shells},
            {"shell_radii", shellRadii(grid)},
            {"shell_min", grid.shellMin},
            {"shell_max", grid.shellMax},
            {"shell_spacing", grid.spacing},
            {"shell_units", "bounding-sphere radius"},
            {"row", "(shell * polar + polar_index) * azimuth + azimuth_index"},
            {"azimuth_angle", "2 pi i / azimuth, d = (sin t sin p, cos t, -sin t cos p)"},
            {"polar_angle", "pi j / (polar - 1) from +Y, both poles included"},
            {"sample", "bounding-sphere centre minus receiver point = rho R d"},
            {"centre", {sphere.centre[0], sphere.centre[1], sphere.centre[2]}},
            {"radius", sphere.radius}};
}

} // namespace prt::fiv
