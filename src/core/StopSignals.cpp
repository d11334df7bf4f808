#include "core/StopSignals.h"

#include <pthread.h>
#include <csignal>
#include <ctime>

namespace terrain {

namespace {
sigset_t stopSet()
{
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    return set;
}
}  // namespace

StopSignals::StopSignals()
{
    const sigset_t set = stopSet();
    pthread_sigmask(SIG_BLOCK, &set, nullptr);
    mThread = std::thread([this] {
        const sigset_t signals = stopSet();
        // Wakes every 50 ms to see whether the object is being destroyed.
        const timespec wait{0, 50'000'000};
        while (!mStop.load(std::memory_order_acquire)) {
            const int signal = sigtimedwait(&signals, nullptr, &wait);
            if (signal > 0) {
                int none = 0;
                mReceived.compare_exchange_strong(none, signal, std::memory_order_acq_rel);
            }
        }
    });
}

StopSignals::~StopSignals()
{
    mStop.store(true, std::memory_order_release);
    mThread.join();
    // The signals stay blocked: unblocking a late one would kill the process on its way out.
}

}  // namespace terrain
