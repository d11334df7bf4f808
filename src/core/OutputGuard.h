// Outputs never overwrite inputs: before a program writes anything it checks that no output path names
// one of its inputs, through any spelling, symbolic link or hard link (AtomicFile's rename would replace
// the input with the output, and the user's source data would be gone).
#pragma once

#include "core/Expected.h"

#include <filesystem>
#include <span>
#include <string>

namespace terrain {

/// An input file and what it is to the user ("height field", "config file"), for messages.
struct InputFile {
    std::string role;
    std::filesystem::path path;
};

/// Whether `a` and `b` are the same file: equal after resolving links, `.` and `..`, or the same inode
/// (hard links). A path that does not exist is the same as another only if both resolve to one name.
bool isSameFile(const std::filesystem::path& a, const std::filesystem::path& b);

/// An error naming both when `output` is one of `inputs` ("the map FILE is the height field FILE"),
/// success otherwise. Inputs with an empty path are skipped. `outputRole` says what would be written there.
Status refuseInputAsOutput(const std::string& outputRole, const std::filesystem::path& output,
                           std::span<const InputFile> inputs);

}  // namespace terrain
