// The hybrid's cone visibility for a table of turns about +Y, so that a runtime (the browser viewer) can turn the
// lights freely with their shadows by blending the two nearest turns.
#include "envlight.h"

#include "core.h"
#include "sh.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace prt::envlight {

uint8_t quantizeVisibility(float visibility) {
    float v = std::clamp(visibility, 0.0f, 1.0f);
    return uint8_t(std::lround(255.0f * v));
}

std::vector<ConeLight> turnConeLightsY(const std::vector<ConeLight>& lights, double degrees) {
    if (degrees == 0.0) return lights;
    double R[9];
    sh::rotationY(degrees, R);
    std::vector<ConeLight> turned = lights;
    for (ConeLight& light : turned) {
        // The JSON's directions are floats (HybridConeLight): the same float in, the same float out.
        double d[3] = {double(float(light.direction[0])), double(float(light.direction[1])),
                       double(float(light.direction[2]))};
        for (int r = 0; r < 3; ++r) light.direction[r] = double(float(R[3 * r] * d[0] + R[3 * r + 1] * d[1] + R[3 * r + 2] * d[2]));
    }
    return turned;
}

std::vector<uint8_t> coneVisibilityTurns(const TriMesh& mesh, const float* points, const float* normals,
                                         const float* spawnNormals, size_t count, const std::vector<ConeLight>& lights,
                                         int samples, int turns, uint64_t* rays, const Surface* surface) {
    if (turns < 1 || turns > kMaxVisibilityTurns)
        throw Error("", "--visibility-turns", std::to_string(turns) + " is outside 1.." +
                                                  std::to_string(kMaxVisibilityTurns), kExitUsage);
    const uint64_t bytes = uint64_t(turns) * uint64_t(count) * uint64_t(lights.size());
    if (count != 0 && lights.size() != 0 && bytes / count / lights.size() != uint64_t(turns)) throw Error("", "--visibility-turns", "table size overflows", kExitUsage);
    if (bytes > kMaxVisibilityTableBytes)
        throw Error("", "--visibility-turns",
                    std::to_string(turns) + " turns x " + std::to_string(count) + " rows x " +
                        std::to_string(lights.size()) + " lights = " + std::to_string(bytes) +
                        " bytes, above the table's limit of " + std::to_string(kMaxVisibilityTableBytes) +
                        " (use fewer turns)",
                    kExitUsage);
    std::vector<uint8_t> table(bytes, 255);
    if (samples == 0 || lights.empty()) return table;
    const size_t layer = count * lights.size();
    uint64_t cast = 0; // every turn's rays
    for (int t = 0; t < turns; ++t) {
        uint64_t turnRays = 0;
        std::vector<float> visibility = coneVisibility(mesh, points, normals, spawnNormals, count,
                                                       turnConeLightsY(lights, t * 360.0 / turns), samples, &turnRays,
                                                       surface);
        cast += turnRays;
        std::transform(visibility.begin(), visibility.end(), table.begin() + t * layer, quantizeVisibility);
    }
    if (rays) *rays = cast;
    return table;
}

} // namespace prt::envlight
