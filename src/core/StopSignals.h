// SIGINT and SIGTERM as a request to stop, not a kill: a long job (a video recording) finishes what it
// has, writes its outputs and exits with 128 + the signal's number. The signals are blocked in every
// thread and taken by one thread of this object with sigtimedwait, so no handler runs in an arbitrary
// thread and there is no global flag.
#pragma once

#include <atomic>
#include <thread>

namespace terrain {

class StopSignals {
public:
    /// Blocks SIGINT and SIGTERM in the calling thread (threads made later inherit that) and starts the
    /// thread that receives them. Construct it in main() before any other thread exists: a thread made
    /// earlier would still take the signals with their default action (exit without the outputs).
    StopSignals();
    /// Stops the receiving thread; the signals stay blocked (a late one is ignored, not fatal).
    ~StopSignals();
    StopSignals(const StopSignals&) = delete;
    StopSignals& operator=(const StopSignals&) = delete;

    /// The first stop signal received (SIGINT or SIGTERM), 0 while none has arrived.
    int received() const { return mReceived.load(std::memory_order_acquire); }
    /// The conventional exit status after it: 128 + the signal number (130 SIGINT, 143 SIGTERM), or 0.
    int exitStatus() const { return received() == 0 ? 0 : 128 + received(); }

private:
    std::atomic<int> mReceived{0};
    std::atomic<bool> mStop{false};
    std::thread mThread;
};

}  // namespace terrain
