// SIGBUS-guarded copies from file mappings: sigsetjmp before the copy, a handler that siglongjmps back
// when the fault lies in the range this thread is copying. Jumping out of memcpy is safe: it holds no
// locks and no state outside its registers.
#include "core/MappedCopy.h"

#include <atomic>
#include <csetjmp>
#include <csignal>
#include <cstdint>
#include <cstring>
#include <mutex>

namespace terrain {

namespace {

/// The copy in progress on this thread, if any: where to jump back to and which source bytes it reads.
/// Thread-local variables of an executable are initial- or local-exec TLS, safe to read in a handler.
struct GuardedCopy {
    sigjmp_buf* jump = nullptr;
    const std::uint8_t* begin = nullptr;
    const std::uint8_t* end = nullptr;
    const std::uint8_t* faultAddress = nullptr;
};
thread_local GuardedCopy tCopy;

struct sigaction gPrevious {};

void onSigbus(int signal, siginfo_t* info, void* context)
{
    const auto* address = static_cast<const std::uint8_t*>(info ? info->si_addr : nullptr);
    if (tCopy.jump && address >= tCopy.begin && address < tCopy.end) {
        tCopy.faultAddress = address;
        siglongjmp(*tCopy.jump, 1);
    }
    // Not ours: behave as if this handler had never been installed.
    if (gPrevious.sa_flags & SA_SIGINFO) {
        if (gPrevious.sa_sigaction) {
            gPrevious.sa_sigaction(signal, info, context);
            return;
        }
    } else if (gPrevious.sa_handler != SIG_DFL && gPrevious.sa_handler != SIG_IGN) {
        gPrevious.sa_handler(signal);
        return;
    }
    // Default action: restore it and re-raise. SA_NODEFER leaves SIGBUS unblocked, so the raise is
    // delivered (and kills) here; a fault that is re-executed after an ignored disposition faults again.
    ::sigaction(SIGBUS, &gPrevious, nullptr);
    ::raise(SIGBUS);
}

void installHandler()
{
    struct sigaction action {};
    action.sa_sigaction = onSigbus;
    action.sa_flags = SA_SIGINFO | SA_NODEFER | SA_ONSTACK;
    sigemptyset(&action.sa_mask);
    ::sigaction(SIGBUS, &action, &gPrevious);
}

/// The copy itself, in a frame of its own with only trivially destructible locals (the longjmp skips it).
bool guardedMemcpy(void* out, const void* mapped, std::size_t size, std::size_t& faultOffset)
{
    sigjmp_buf jump;
    const auto* begin = static_cast<const std::uint8_t*>(mapped);
    // Save and restore the signal mask: the jump leaves the handler without the kernel's sigreturn, so
    // whatever the handler ran with (nothing more with SA_NODEFER, but a sanitizer's wrapper blocks every
    // signal) would otherwise stay blocked in this thread and in every thread it starts.
    if (sigsetjmp(jump, 1) != 0) {
        faultOffset = static_cast<std::size_t>(tCopy.faultAddress - begin);
        tCopy = {};
        return false;
    }
    tCopy = {&jump, begin, begin + size, nullptr};
    std::atomic_signal_fence(std::memory_order_seq_cst);  // the guard is up before the first read
    std::memcpy(out, mapped, size);
    std::atomic_signal_fence(std::memory_order_seq_cst);  // and down only after the last
    tCopy = {};
    return true;
}

}  // namespace

Status copyFromMapping(void* out, const void* mapped, std::size_t size)
{
    static std::once_flag installed;
    std::call_once(installed, installHandler);
    std::size_t faultOffset = 0;
    if (!guardedMemcpy(out, mapped, size, faultOffset)) {
        return makeError("a page of the mapping at byte ", faultOffset, " of this ", size,
                         "-byte read is no longer backed by the file (it was truncated while mapped)");
    }
    return {};
}

}  // namespace terrain
