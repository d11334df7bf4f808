// The detail_* options turned into a DetailSynthesizer (paper 3.4, Appendix A): shared by tengine and
// tengine-tool, so a height query sees exactly what the viewer draws.
#pragma once

#include "apps/TengineOptions.h"
#include "core/Expected.h"
#include "synthesis/DetailSynthesizer.h"

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace terrain {

/// The material files the options select: detail_materials, or the built-in material of
/// detail_material_type (0 grass.mat, 1 rock.mat) in material_path (or `builtInDirectory` when empty).
std::vector<std::filesystem::path> detailMaterialFiles(const TengineOptions& options,
                                                       const std::filesystem::path& builtInDirectory);

/// The synthesizer for `options` and the map with `header` (its chunk size; with detail_roughness, its
/// roughness grid), or null when detail_create_new_nodes is off. With detail_add_material off, no materials.
/// A single material covers the whole terrain whatever its placement rules. Material warnings go to
/// `warnings`; errors name the file and line.
Expected<std::unique_ptr<const DetailSynthesizer>> makeDetailSynthesizer(const TengineOptions& options,
                                                                         const MapHeader& header,
                                                                         const std::filesystem::path& builtInDirectory,
                                                                         std::vector<std::string>& warnings);

/// The material files `synthesizer` (made by makeDetailSynthesizer from `options`) displaces with, in
/// order; empty with detail_add_material off.
std::vector<std::filesystem::path> synthesizedMaterialFiles(const TengineOptions& options,
                                                            const DetailSynthesizer& synthesizer,
                                                            const std::filesystem::path& builtInDirectory);

/// The recipe of what the viewer synthesizes (3.4.1): scheme, omega and the materials detailMaterialFiles()
/// names (none with detail_add_material off). Errors name an unreadable material file.
Expected<DetailRecipe> viewerDetailRecipe(const TengineOptions& options, const DetailSynthesizer& synthesizer,
                                          const std::filesystem::path& builtInDirectory);

/// The one warning the viewer gives when the map's detail errors were estimated for other settings than
/// its own (or the map does not say what for): both recipes and the prep command that would match.
/// Empty when they agree. `mapName` names the map in the message.
std::optional<std::string> detailRecipeMismatch(const MapHeader& header, const std::string& mapName,
                                                const DetailRecipe& viewer,
                                                const std::vector<std::filesystem::path>& viewerFiles);

}  // namespace terrain
