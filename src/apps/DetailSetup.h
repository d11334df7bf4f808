// The detail_* options turned into a DetailSynthesizer (paper 3.4, Appendix A): shared by tengine and
// tengine-tool, so a height query sees exactly what the viewer draws.
#pragma once

#include "apps/TengineOptions.h"
#include "core/Expected.h"
#include "synthesis/DetailSynthesizer.h"

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace terrain {

/// The material files the options select: detail_materials, or the built-in material of
/// detail_material_type (0 grass.mat, 1 rock.mat) in material_path (or `builtInDirectory` when empty).
std::vector<std::filesystem::path> detailMaterialFiles(const TengineOptions& options,
                                                       const std::filesystem::path& builtInDirectory);

/// The synthesizer for `options` and chunk size N, or null when detail_create_new_nodes is off. With
/// detail_add_material off, subdivision only. A single material covers the whole terrain whatever its
/// placement rules. Material warnings go to `warnings`; errors name the file and line.
Expected<std::unique_ptr<const DetailSynthesizer>> makeDetailSynthesizer(const TengineOptions& options, int chunkSize,
                                                                         const std::filesystem::path& builtInDirectory,
                                                                         std::vector<std::string>& warnings);

}  // namespace terrain
