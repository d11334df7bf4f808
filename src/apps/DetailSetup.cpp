#include "apps/DetailSetup.h"

#include "core/Parse.h"
#include "synthesis/DetailRecipeSetup.h"

namespace terrain {

std::vector<std::filesystem::path> detailMaterialFiles(const TengineOptions& options,
                                                       const std::filesystem::path& builtInDirectory)
{
    if (!options.detailMaterials.empty()) {
        return options.detailMaterials;
    }
    const std::filesystem::path directory = options.materialPath.empty() ? builtInDirectory : options.materialPath;
    return {directory / (options.detailMaterialType == 0 ? "grass.mat" : "rock.mat")};
}

Expected<std::unique_ptr<const DetailSynthesizer>> makeDetailSynthesizer(const TengineOptions& options,
                                                                         const MapHeader& header,
                                                                         const std::filesystem::path& builtInDirectory,
                                                                         std::vector<std::string>& warnings)
{
    if (!options.detailCreateNewNodes) {
        return std::unique_ptr<const DetailSynthesizer>();
    }
    DetailSettings settings;
    settings.scheme = options.detailSubdivisionScheme;
    settings.omega = options.detailSubdivisionFactor;
    if (options.detailAddMaterial) {
        auto materials = loadDetailMaterials(detailMaterialFiles(options, builtInDirectory), warnings);
        TERRAIN_TRY(materials);
        settings.materials = std::move(materials).value();
    }
    if (settings.materials && settings.materials->hasRelative() && !header.roughness) {
        for (const Material& m : settings.materials->materials()) {
            if (m.relativeAmplitude > 0.0 && m.displacement) {
                warnings.push_back(m.file + ": relative_amplitude needs the terrain's roughness laws, which the map " +
                                   "does not have (made before map format 5): material " + m.name +
                                   " uses its amplitude of " + formatNumber(m.fractal.amplitude) + " m instead");
            }
        }
    }
    // Relative materials follow the map's roughness laws; detail_roughness continues them below the leaves.
    return DetailSynthesizer::create(static_cast<int>(header.chunkSize),
                                     settingsForMap(std::move(settings), header, options.detailRoughness));
}

std::vector<std::filesystem::path> synthesizedMaterialFiles(const TengineOptions& options,
                                                            const DetailSynthesizer& synthesizer,
                                                            const std::filesystem::path& builtInDirectory)
{
    return synthesizer.settings().materials ? detailMaterialFiles(options, builtInDirectory)
                                            : std::vector<std::filesystem::path>{};
}

Expected<DetailRecipe> viewerDetailRecipe(const TengineOptions& options, const DetailSynthesizer& synthesizer,
                                          const std::filesystem::path& builtInDirectory)
{
    auto recipe =
        makeDetailRecipe(synthesizer.settings(), synthesizedMaterialFiles(options, synthesizer, builtInDirectory));
    TERRAIN_TRY(recipe);
    recipe->roughness = synthesizer.settings().roughness != nullptr;
    return recipe;
}

std::optional<std::string> detailRecipeMismatch(const MapHeader& header, const std::string& mapName,
                                                const DetailRecipe& viewer,
                                                const std::vector<std::filesystem::path>& viewerFiles)
{
    if (header.detailRecipe && header.detailRecipe->sameSynthesis(viewer)) {
        return std::nullopt;
    }
    std::string command = "prep HEIGHTFIELD -h " + formatNumber(header.sampleSpacing);
    if (header.chunkSize != 65) {
        command += " --chunk " + std::to_string(header.chunkSize);
    }
    for (const auto& file : viewerFiles) {
        command += " --material " + file.string();
    }
    if (viewerFiles.empty()) {
        command += " --no-material";
    }
    if (!viewer.roughness) {
        command += " --no-roughness";
    }
    if (viewer.scheme != "kobbelt") {
        command += " --detail-scheme " + viewer.scheme;
    } else if (viewer.omega != 1.0) {
        command += " --detail-factor " + formatNumber(viewer.omega);
    }
    command += " -o " + mapName;
    const std::string assumed = header.detailRecipe ? "were estimated for " + header.detailRecipe->describe()
                                                    : "do not say what synthesis they assume (made by an older prep)";
    return mapName + ": the detail errors below its leaves " + assumed + ", but the viewer synthesizes " +
           viewer.describe() + ": the level of detail may not hold tau below the data; to match, run: " + command;
}

}  // namespace terrain
