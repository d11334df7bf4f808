// Shader files as the GL is given them: `#include "name"` lines replaced by the named file (docs/design.md,
// "GL code"). Pure: no GL here, so unit tests read the shaders without a context.
#pragma once

#include "core/Expected.h"

#include <filesystem>
#include <string>

namespace terrain {

/// A shader file's text with each `#include "name"` line replaced by the named file's text (from the same
/// directory; one level: an included file includes nothing), `#line` directives keeping the driver's line
/// numbers those of each file. Errors name the file and line.
Expected<std::string> readShaderFile(const std::filesystem::path& file);

}  // namespace terrain
