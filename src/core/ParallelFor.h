// Data-parallel loops over independent items (prep's per-node work). Threads are created per call and
// joined before it returns: no pool, no global state.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace terrain {

/// Calls body(i) for every i in [0, count) on up to `threads` threads (the caller's included); items are
/// handed out one at a time in increasing order. Returns when all are done. The first exception thrown by
/// a body is rethrown here after all threads finish.
template <class Body>
void parallelFor(std::size_t count, int threads, Body&& body)
{
    std::atomic<std::size_t> next{0};
    std::exception_ptr failure;
    std::mutex failureMutex;
    auto work = [&] {
        for (std::size_t i = next++; i < count; i = next++) {
            try {
                body(i);
            } catch (...) {
                std::lock_guard lock(failureMutex);
                if (!failure) {
                    failure = std::current_exception();
                }
            }
        }
    };
    std::size_t helpers = std::min<std::size_t>(count, static_cast<std::size_t>(std::max(threads, 1)));
    std::vector<std::thread> pool;
    for (std::size_t t = 1; t < helpers; ++t) {
        pool.emplace_back(work);
    }
    work();
    for (auto& thread : pool) {
        thread.join();
    }
    if (failure) {
        std::rethrow_exception(failure);
    }
}

/// A sensible default thread count: the hardware's, at least 1.
inline int defaultThreadCount()
{
    return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

}  // namespace terrain
