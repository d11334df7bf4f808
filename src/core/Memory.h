// Memory budget checks: an input that cannot fit is refused before any allocation, with a message saying
// why (docs/design.md, "Errors", kind 3).
#pragma once

#include "core/Expected.h"

#include <cstdint>
#include <string>
#include <string_view>

namespace terrain {

/// Bytes of memory the system can give this process now (MemAvailable from /proc/meminfo, else physical
/// memory), no more than the address space left under RLIMIT_AS (`ulimit -v`) when one is set. Never 0.
std::uint64_t availableMemoryBytes();

/// Fails, naming `what`, when `bytes` exceeds the memory available now. Call before large allocations.
Status checkAllocation(std::uint64_t bytes, std::string_view what);

/// Peak resident set size of this process so far, in bytes (getrusage).
std::uint64_t peakResidentBytes();

/// Resident set size of this process now, in bytes (/proc/self/statm); 0 if unknown.
std::uint64_t currentResidentBytes();

/// "1.5 GiB", "12.0 MiB", "300 B".
std::string formatBytes(std::uint64_t bytes);

}  // namespace terrain
