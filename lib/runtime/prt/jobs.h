// prt/jobs.h: the hook through which an engine lends the runtime its own job system. The runtime starts no threads:
// a function that can use several cores splits its work into a fixed number of independent tasks (a function of
// the input alone, never of the hook or of the machine) and hands them to the hook, or, without one, runs them
// in order on the calling thread. Each task writes only its own part of the output, so results are bit-identical
// whatever the hook does: serial, parallel, in any order. std only.
#pragma once

#include <cstddef>

namespace prt {

// Runs task(taskData, i) once for each i in [0, taskCount), on any threads, in any order, and returns when all have
// returned. Tasks never throw (the runtime catches inside them) and are independent of each other.
using TaskFunction = void (*)(void* taskData, size_t index);
using ParallelFor = void (*)(void* context, size_t taskCount, TaskFunction task, void* taskData);

struct JobSystem {
    ParallelFor parallelFor = nullptr; // null: run the tasks in order on the calling thread
    void* context = nullptr;           // passed to parallelFor unchanged (the engine's scheduler, say)
};

// Runs the tasks as `jobs` says (serially when jobs.parallelFor is null).
inline void runTasks(const JobSystem& jobs, size_t taskCount, TaskFunction task, void* taskData) {
    if (jobs.parallelFor) {
        jobs.parallelFor(jobs.context, taskCount, task, taskData);
        return;
    }
    for (size_t i = 0; i < taskCount; ++i) task(taskData, i);
}

} // namespace prt
