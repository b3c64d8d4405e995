// prt/lighting.h: SH lighting for the runtime: prt-sh JSON, environment maps, rotation and order matching.
#pragma once

#include "image.h" // EnvironmentMap
#include "sh.h"    // sh::Window

#include <string>
#include <vector>

namespace prt {

// Lighting of `coefficientCount` RGB coefficients from lighting of another count: their common prefix, with
// missing coefficients set to zero. Both counts are squares, so this is projecting both onto their common bands.
// Throws prt::Error for a count outside 0..sh::kMaxOrder^2.
std::vector<float> fitLighting(const float* lighting, int lightingCoefficientCount, int coefficientCount);

// Reads prt-sh JSON as `prt envsh` writes it ({"format":"prt-sh","order":L,"coefficients":[[r,g,b],...]}).
// Returns [L*L][3] and sets *order to L. Throws prt::Error naming the file and the bad member.
std::vector<float> readLightingJson(const std::string& path, int* order);

// Lighting for `order` bands from an environment map: projected with exact texel solid angles, then rotated so
// the environment turns by `rotation` (row-major 3x3, d' = R d; null for none), then windowed against ringing.
std::vector<float> environmentLighting(const EnvironmentMap& env, int order, const double* rotation,
                                       sh::Window window);

// Rotates RGB lighting of `order` bands so the environment it describes turns by `rotation` (d' = R d).
std::vector<float> rotateLighting(const float* lighting, int order, const double rotation[9]);


} // namespace prt
