// One way to turn material files and subdivision settings into what synthesis uses and what the map
// records (3.4.1): prep and the viewer both call these, so `prep x.png` then `tengine x.map` synthesize
// the same detail, and the recipe prep stores can be compared with the viewer's.
#pragma once

#include "core/Expected.h"
#include "quadtree/MapFormat.h"
#include "synthesis/DetailSynthesizer.h"
#include "synthesis/Material.h"

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace terrain {

/// FNV-1a (64 bits) of the file's bytes. Errors name the file.
Expected<std::uint64_t> hashFileContent(const std::filesystem::path& path);

/// The materials of `files` (at least one) as detail synthesis uses them: one file is the ground
/// everywhere, so its placement rules (which have nothing to blend with) are dropped; several are placed
/// and blended by their rules, the first the ground. Errors name the file and line.
Expected<std::shared_ptr<const MaterialSet>> loadDetailMaterials(const std::vector<std::filesystem::path>& files,
                                                                 std::vector<std::string>& warnings);

/// The recipe of `settings` whose materials were loaded from `files` (in the same order; both empty for
/// subdivision only): scheme, omega, and each material's name with the hash of its file.
Expected<DetailRecipe> makeDetailRecipe(const DetailSettings& settings,
                                        const std::vector<std::filesystem::path>& files);

}  // namespace terrain
