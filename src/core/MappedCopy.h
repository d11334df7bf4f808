// Copying out of a memory-mapped file that another process may truncate (Appendix A `reader =
// memory_mapped`). Touching a mapped page that lies wholly past the file's current end raises SIGBUS,
// which would kill the viewer; this turns it into an error for the one copy that touched the page.
#pragma once

#include "core/Expected.h"

#include <cstddef>

namespace terrain {

/// Copies `size` bytes from `mapped` (inside a read-only file mapping) to `out`. When the copy touches a
/// page past the end of the mapped file (it was truncated after mapping), fails with "a page of the
/// mapping at byte offset K of this copy is no longer backed by the file" instead of dying of SIGBUS;
/// the bytes of `out` are then unspecified. Callers prefix the file and what was being read.
///
/// Thread-safe. The first call installs a process-wide SIGBUS handler (SA_SIGINFO | SA_NODEFER) that
/// acts only on faults inside a guarded copy on the faulting thread; any other SIGBUS is handed to the
/// disposition that was installed before, so a program's own crashes still crash.
Status copyFromMapping(void* out, const void* mapped, std::size_t size);

}  // namespace terrain
