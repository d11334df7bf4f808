#include "GlTestSupport.h"

#include "TestSupport.h"
#include "heightfield/HeightFieldIo.h"
#include "quadtree/QuadtreeBuilder.h"
#include "synthesis/DetailErrorModel.h"
#include "synthesis/DetailRecipeSetup.h"
#include "synthesis/LeafErrorEstimator.h"

#include <glm/geometric.hpp>

#include <cmath>
#include <fstream>
#include <sstream>

namespace terrain::test {

Status buildDemoMap(const std::filesystem::path& path, const std::vector<std::filesystem::path>& materials)
{
    auto field = readHeightField(demoDataPath("trinidad_co_srtm3_crop_1025.png"));
    TERRAIN_TRY(field);
    return buildDetailMap(std::move(field).value(), 90.0, path, materials);
}

Expected<std::unique_ptr<GlWindow>> openHiddenWindow(int width, int height)
{
    WindowOptions options;
    options.width = width;
    options.height = height;
    options.visible = false;
    return GlWindow::create(options);
}

Expected<std::unique_ptr<DemoScene>> openDemoScene(int width, int height)
{
    auto scene = std::make_unique<DemoScene>();
    const std::filesystem::path path = scene->dir / "trinidad.map";
    TERRAIN_TRY(buildDemoMap(path));
    auto window = openHiddenWindow(width, height);
    TERRAIN_TRY(window);
    scene->window = std::move(window).value();
    auto map = MapFile::open(path, ReaderKind::Stream);
    TERRAIN_TRY(map);
    scene->map = std::move(map).value();
    return scene;
}

Status buildDetailMap(HeightField field, double spacing, const std::filesystem::path& path,
                      const std::vector<std::filesystem::path>& materials, const std::filesystem::path& texture)
{
    BuildOptions options;
    options.spacing = spacing;
    if (!texture.empty()) {
        options.texture = texture;
    }
    options.threads = 2;
    std::unique_ptr<const DetailSynthesizer> synthesizer;
    if (!materials.empty()) {
        std::vector<std::string> warnings;
        auto set = loadDetailMaterials(materials, warnings);
        TERRAIN_TRY(set);
        const DetailSettings settings{"kobbelt", 1.0, std::move(set).value()};
        auto made = DetailSynthesizer::create(65, settings);
        TERRAIN_TRY(made);
        synthesizer = std::move(made).value();
        auto recipe = makeDetailRecipe(settings, materials);
        TERRAIN_TRY(recipe);
        // As prep makes it: the errors include the roughness the viewer continues (detail_roughness).
        recipe->roughness = true;
        options.leafDetailError = leafDetailErrorFunction(*synthesizer, true);
        options.detailDisplacementRangeFor = detailDisplacementRangeFunction(*synthesizer);
        options.detailRecipe = std::move(recipe).value();
    }
    auto built = buildMap(std::move(field), options, path);
    TERRAIN_TRY(built);
    return {};
}

bool mustHitTerrain(const Camera& camera, const MapHeader& header, double zMin, int px, int py)
{
    const double ndcX = (px + 0.5) / camera.viewportWidth * 2 - 1;
    const double ndcY = 1 - (py + 0.5) / camera.viewportHeight * 2;
    const double tanHalf = std::tan(camera.verticalFov / 2);
    const glm::dvec3 direction = glm::normalize(camera.forward() + camera.right() * (ndcX * tanHalf * camera.aspect()) +
                                                camera.up() * (ndcY * tanHalf));
    if (direction.z >= -1e-6) {
        return false;
    }
    const double t = (zMin - camera.position.z) / direction.z;
    const glm::dvec3 hit = camera.position + t * direction;
    const double depth = t * glm::dot(direction, camera.forward());
    const double s = header.sampleSpacing;
    const double margin = 2 * s;
    return depth < camera.farPlane * 0.98 && hit.x > header.originX + margin && hit.y > header.originY + margin &&
           hit.x < header.originX + (header.validWidth - 1) * s - margin &&
           hit.y < header.originY + (header.validHeight - 1) * s - margin;
}

std::vector<std::map<std::string, double>> readCsv(const std::filesystem::path& file)
{
    std::ifstream in(file);
    std::string line;
    std::getline(in, line);
    std::vector<std::string> names;
    for (std::stringstream header(line); std::getline(header, line, ',');) {
        names.push_back(line);
    }
    std::vector<std::map<std::string, double>> rows;
    while (std::getline(in, line)) {
        std::stringstream fields(line);
        std::map<std::string, double> row;
        for (const auto& name : names) {
            std::string value;
            std::getline(fields, value, ',');
            if (!value.empty()) {  // empty: not measured in this frame (error_max_px, ...)
                row[name] = std::stod(value);
            }
        }
        rows.push_back(std::move(row));
    }
    return rows;
}

}  // namespace terrain::test
