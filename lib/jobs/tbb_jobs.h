// The job system prt's own programs lend the runtime (prt/jobs.h): TBB's scheduler, which the stages already use.
// The runtime itself starts no threads and stays free of TBB; this header is for the CLI and lib/render, which link
// TBB anyway. Results are bit-identical to a serial run whatever TBB does (the runtime's tasks write disjoint rows).
#pragma once

#include "prt/jobs.h"

#include <tbb/parallel_for.h>

namespace prt {

// A JobSystem whose parallelFor runs the `count` tasks on TBB's scheduler and returns when all are done. Needs
// nothing; guarantees every task index in [0, count) runs exactly once, on any thread.
inline JobSystem tbbJobs() {
    JobSystem jobs;
    jobs.parallelFor = [](void*, size_t count, TaskFunction task, void* data) {
        tbb::parallel_for(size_t(0), count, [&](size_t i) { task(data, i); });
    };
    return jobs;
}

} // namespace prt
