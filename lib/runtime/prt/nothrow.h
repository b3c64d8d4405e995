// prt/nothrow.h: the runtime's loaders and relight without exceptions, for engines built with -fno-exceptions.
// Each function does what its namesake in prt/relight.h, prt/texels.h or prt/lighting.h does and returns a Status
// (prt/status.h) instead of throwing: NotFound for a file that does not exist, Corrupt for one that is not a valid
// bundle or lighting file or whose layers are malformed, InvalidInput for arguments outside the function's needs,
// OutOfMemory, Internal. They never throw; the message is the throwing variant's. std only.
#pragma once

#include "jobs.h"
#include "relight.h"
#include "status.h"
#include "texels.h"

#include <cstddef>
#include <string>
#include <vector>

namespace prt {

Expected<RelightModel> tryLoadRelightModel(const std::string& bundlePath) noexcept;
// The in-bundle texel rows (texelRelightModel's reach: no image library).
Expected<TexelRelightModel> tryLoadTexelRelightModel(const std::string& bundlePath) noexcept;
// readLightingJson: [L*L][3] coefficients; *order set to L on success.
Expected<std::vector<float>> tryReadLightingJson(const std::string& path, int* order) noexcept;
// relight(model, ...); also InvalidInput for a null lighting or radiance pointer.
Status tryRelight(const RelightModel& model, const float* lighting, size_t begin, size_t end, float* radiance,
                  const JobSystem& jobs = {}) noexcept;

} // namespace prt
