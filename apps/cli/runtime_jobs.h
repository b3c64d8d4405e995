// The job system the CLI lends the runtime (prt/jobs.h): TBB's scheduler, which the stages already use. The runtime
// itself starts no threads; results are bit-identical to a serial run whatever TBB does.
#pragma once

#include "prt/jobs.h"

#include <tbb/parallel_for.h>

namespace prt::cli {

inline JobSystem tbbJobs() {
    JobSystem jobs;
    jobs.parallelFor = [](void*, size_t count, TaskFunction task, void* data) {
        tbb::parallel_for(size_t(0), count, [&](size_t i) { task(data, i); });
    };
    return jobs;
}

} // namespace prt::cli
