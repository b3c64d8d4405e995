// parallelBlocks: a plain std::thread pool over numbered blocks, for code that must not depend on TBB.
#include "core.h"

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>
#include <thread>

namespace prt {

void parallelBlocks(size_t blockCount, int threads, const std::function<void(size_t block)>& work) {
    size_t workers = threads > 0 ? size_t(threads) : std::max(1u, std::thread::hardware_concurrency());
    workers = std::min(workers, blockCount);
    if (workers <= 1) {
        for (size_t block = 0; block < blockCount; ++block) work(block);
        return;
    }
    std::atomic<size_t> next{0};
    std::exception_ptr failure;
    std::mutex failureMutex;
    auto run = [&] {
        for (size_t block; (block = next.fetch_add(1)) < blockCount;) {
            try {
                work(block);
            } catch (...) {
                std::lock_guard<std::mutex> lock(failureMutex);
                if (!failure) failure = std::current_exception();
                next = blockCount; // the others stop after their current block
            }
        }
    };
    std::vector<std::thread> pool;
    for (size_t i = 1; i < workers; ++i) pool.emplace_back(run);
    run();
    for (std::thread& thread : pool) thread.join();
    if (failure) std::rethrow_exception(failure);
}

} // namespace prt
