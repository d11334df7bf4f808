// Child processes without a shell: an argument vector goes to posix_spawnp as it is, so no file name is
// ever parsed by /bin/sh (spaces, quotes, `$` and `;` in paths are just characters).
#pragma once

#include "core/Expected.h"

#include <filesystem>
#include <string>
#include <vector>

namespace terrain {

/// The executable `name` would run as (searched on PATH), or empty when there is none.
std::filesystem::path findOnPath(const std::string& name);

/// Runs `argv` (argv[0] searched on PATH) with stdin from /dev/null and the parent's stdout and stderr,
/// every signal unblocked and at its default disposition, and waits for it. Returns its exit status
/// (0-255), or an error when it could not start or was killed by a signal. `argv` must not be empty.
Expected<int> runProcess(const std::vector<std::string>& argv);

}  // namespace terrain
