// prep's command line (paper 4.4.1): its flag table (CommandLine.h), every number range-checked, and the
// --help text generated from the table.
#pragma once

#include "core/Expected.h"
#include "heightfield/HeightFieldIo.h"
#include "quadtree/QuadtreeBuilder.h"
#include "synthesis/DetailSynthesizer.h"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace terrain {

/// The most worker threads prep takes (--threads): more than any machine it runs on has cores.
inline constexpr int kMaxPrepThreads = 1024;

/// What prep's arguments ask for.
struct PrepArguments {
    std::vector<std::filesystem::path> inputs;    ///< the height field(s), at least one
    std::optional<std::filesystem::path> output;  ///< -o
    BuildOptions build;
    HeightFieldReadOptions read;
    DetailSettings detail;                         ///< --detail-scheme, --detail-factor (materials aside)
    std::vector<std::string> warnings;             ///< about options that have no effect
    std::vector<std::filesystem::path> materials;  ///< --material, or the default material
    bool noMaterial = false;                       ///< --no-material
    bool noRoughness = false;                      ///< --no-roughness
};

/// Parses prep's arguments (without the program name). build.threads defaults to `defaultThreads`; without
/// --material or --no-material, materials holds `defaultMaterial` (the viewer's default). Errors name the
/// flag and what was wrong: a missing value, a value out of its range (NaN, infinities, empty and huge
/// values included), an unknown option, no height field, --no-material with --material.
Expected<PrepArguments> parsePrepArguments(const std::vector<std::string>& arguments, int defaultThreads,
                                           const std::filesystem::path& defaultMaterial);

/// prep --help.
std::string prepUsage();

}  // namespace terrain
