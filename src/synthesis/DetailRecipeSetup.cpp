#include "synthesis/DetailRecipeSetup.h"

#include "core/Check.h"

#include <cerrno>
#include <cstring>
#include <fstream>

namespace terrain {

Expected<std::uint64_t> hashFileContent(const std::filesystem::path& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        return makeError(path.string(), ": cannot read: ", std::strerror(errno));
    }
    std::uint64_t hash = 0xcbf29ce484222325ull;  // FNV-1a 64 offset basis and prime
    char buffer[1 << 14];
    while (in.read(buffer, sizeof buffer) || in.gcount() > 0) {
        for (std::streamsize i = 0; i < in.gcount(); ++i) {
            hash = (hash ^ static_cast<std::uint8_t>(buffer[i])) * 0x100000001b3ull;
        }
    }
    if (in.bad()) {
        return makeError(path.string(), ": read error");
    }
    return hash;
}

Expected<std::shared_ptr<const MaterialSet>> loadDetailMaterials(const std::vector<std::filesystem::path>& files,
                                                                 std::vector<std::string>& warnings)
{
    TERRAIN_EXPECTS(!files.empty(), "loadDetailMaterials: at least one material file");
    auto set = MaterialSet::load(files, warnings);
    TERRAIN_TRY(set);
    if (files.size() == 1) {
        std::vector<Material> materials = set->materials();
        materials.front().placement = MaterialPlacement{};
        return std::make_shared<const MaterialSet>(std::move(materials));
    }
    return std::make_shared<const MaterialSet>(std::move(set).value());
}

Expected<DetailRecipe> makeDetailRecipe(const DetailSettings& settings, const std::vector<std::filesystem::path>& files)
{
    const std::size_t count = settings.materials ? settings.materials->materials().size() : 0;
    TERRAIN_EXPECTS(count == files.size(), "makeDetailRecipe: one file per material, in order");
    DetailRecipe recipe;
    recipe.scheme = settings.scheme;
    recipe.omega = settings.omega;
    for (std::size_t i = 0; i < count; ++i) {
        auto hash = hashFileContent(files[i]);
        TERRAIN_TRY(hash);
        recipe.materials.push_back({settings.materials->materials()[i].name, *hash});
    }
    return recipe;
}

}  // namespace terrain
