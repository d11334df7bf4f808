// Where the programs find their shaders and built-in materials: beside an installed executable
// (<prefix>/bin/tengine -> <prefix>/share/tengine/shaders, what `cmake --install` lays out), else in the
// source tree they were built from (compiled in), so a build runs in place and an install runs anywhere.
#pragma once

#include <filesystem>
#include <string_view>

namespace terrain {

/// `kind` ("shaders" or "materials") under the install's data directory when this process's executable
/// lies in an installed bin directory that has it, else `sourceTree`.
std::filesystem::path programDataDirectory(std::string_view kind, const std::filesystem::path& sourceTree);

}  // namespace terrain
