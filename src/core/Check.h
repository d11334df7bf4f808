// Preconditions and internal invariants (docs/design.md, "Errors", kinds 1 and 2). Both stay on in release
// builds: a broken precondition is a caller's bug and must not turn into silent memory corruption.
#pragma once

#include <cstdio>
#include <cstdlib>

namespace terrain::detail {
[[noreturn]] inline void checkFailed(const char* kind, const char* expr, const char* message, const char* file,
                                     int line)
{
    std::fprintf(stderr, "%s:%d: %s failed: %s (%s)\n", file, line, kind, expr, message);
    std::abort();
}
}  // namespace terrain::detail

/// A documented precondition of a public function; `message` says what the caller got wrong.
#define TERRAIN_EXPECTS(cond, message)                                                          \
    do {                                                                                        \
        if (!(cond)) {                                                                          \
            ::terrain::detail::checkFailed("precondition", #cond, message, __FILE__, __LINE__); \
        }                                                                                       \
    } while (false)

/// An internal invariant: failing means a bug in this code base.
#define TERRAIN_ASSERT(cond)                                                                          \
    do {                                                                                              \
        if (!(cond)) {                                                                                \
            ::terrain::detail::checkFailed("assertion", #cond, "internal error", __FILE__, __LINE__); \
        }                                                                                             \
    } while (false)
