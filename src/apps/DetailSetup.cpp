#include "apps/DetailSetup.h"

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

Expected<std::unique_ptr<const DetailSynthesizer>> makeDetailSynthesizer(const TengineOptions& options, int chunkSize,
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
        const auto files = detailMaterialFiles(options, builtInDirectory);
        auto set = MaterialSet::load(files, warnings);
        TERRAIN_TRY(set);
        if (files.size() == 1) {
            // One material is the ground everywhere (as in the paper): its placement rules have nothing to
            // blend with.
            std::vector<Material> materials = set->materials();
            materials.front().placement = MaterialPlacement{};
            settings.materials = std::make_shared<const MaterialSet>(std::move(materials));
        } else {
            settings.materials = std::make_shared<const MaterialSet>(std::move(set).value());
        }
    }
    return DetailSynthesizer::create(chunkSize, std::move(settings));
}

}  // namespace terrain
