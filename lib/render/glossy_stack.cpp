// The glossy runtime's prefiltered environment as prt render builds it, and its sharpness stack written out for
// the browser viewer (viewer/glossy.js reads it), so that the viewer looks lobes up in the very texels prt does.
#include "render.h"

#include "core.h"
#include "runtime.h"
#include "tbb_jobs.h"

#include <cstring>
#include <string>

namespace prt {

PrefilteredEnvironment glossyRenderEnvironment(const GlossyModel& glossy, const EnvironmentMap& environment,
                                               const std::string& envSource) {
    if (environment.layout != EnvLayout::Equirectangular)
        throw Error(envSource, "--env", "the glossy runtime needs an equirectangular (2:1) map");
    PrefilterOptions options;
    glossySharpnessRange(glossy, options.sharpnessMin, options.sharpnessMax);
    const JobSystem jobs = tbbJobs();
    options.jobs = &jobs;
    return prefilterEnvironment(environment.radiance.rgb.data(), environment.radiance.width,
                                environment.radiance.height, options);
}

void writeSharpnessStack(const std::string& path, const PrefilteredEnvironment& env) {
    if (env.sharpnessLevels.size() < 2)
        throw Error(path, "--glossy-stack", "no sharpness stack to write (the lobes have no lit sharpness range)");
    std::string bytes = "PRTSGSTK";
    auto put = [&](const void* data, size_t size) { bytes.append(static_cast<const char*>(data), size); };
    auto putU32 = [&](uint32_t value) { put(&value, 4); }; // little-endian hosts only (as every prt binary file)
    putU32(1);
    putU32(uint32_t(env.levelsPerOctave));
    putU32(uint32_t(env.firstSharpnessIndex));
    putU32(uint32_t(env.sharpnessLevels.size()));
    for (const PrefilteredEnvironment::SharpnessLevel& level : env.sharpnessLevels) {
        putU32(uint32_t(level.width));
        putU32(uint32_t(level.height));
        put(&level.sharpness, 8);
        put(level.rgb.data(), level.rgb.size() * sizeof(float));
    }
    writeBytesAtomic(path, bytes);
}

} // namespace prt
