// The detail bounds hold (synthesis/DetailErrorModel.h): over random nodes below the static data, static
// leaves (prep's estimate, stored in the map) and dynamic nodes (the viewer's, lod/TerrainNodeSource.h), the
// largest vertical distance of the node's triangulated surface from its descendants synthesized three levels
// down, at every one of their samples, is within the node's delta_c. Three kinds of data: the bundled terrain
// (90 m SRTM), a 16x decimated copy of it (1440 m) and a 9 km grid under the highest mountains of ETOPO5, each
// with the demo's materials (grass, rock) relative to the terrain's roughness, continued below the data.
// The node's bounding box holds those descendants too. Prints, per level, the nodes measured and the median and largest
// measured / bound (how tight it is).
#include "MapTestSupport.h"
#include "TestSupport.h"

#include "heightfield/HeightFieldIo.h"
#include "lod/TerrainNodeSource.h"
#include "quadtree/MapFile.h"
#include "quadtree/QuadtreeBuilder.h"
#include "quadtree/TemplateTriangulation.h"
#include "synthesis/DetailErrorModel.h"
#include "synthesis/DetailRecipeSetup.h"
#include "synthesis/DetailSynthesizer.h"
#include "synthesis/NormalMap.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

namespace terrain {
namespace {

constexpr int kN = 65;
/// Levels below the node of the reference: the node's children (measured by the bound itself) and two more.
constexpr int kReferenceDepth = 3;
/// Levels below the static leaves that the walks visit.
constexpr int kDynamicLevels = 12;

HeightField decimate(const HeightField& field, int factor)
{
    const int w = (field.width - 1) / factor + 1, h = (field.height - 1) / factor + 1;
    return test::makeHeightField(w, h, [&](int i, int j) { return field.at(i * factor, j * factor); });
}

/// What the surface kReferenceDepth levels below a node does over the node's square: its largest distance
/// from the node's triangulated surface, and its lowest and highest sample (metres above the map's offset).
struct Reference {
    double error = 0.0;
    double lowest = 0.0, highest = 0.0;
};

Reference measure(const DetailSynthesizer& synthesizer, const NodeData& node, const WindowPlacement& where)
{
    const int w = synthesizer.windowSize();
    const int below = kReferenceDepth - 1;  // surfaceBelow's depth under each child
    const int childCells = (kN - 1) << below;
    const int wc = childCells + 1 + 2 * kBorder;
    const double step = 1.0 / (1 << kReferenceDepth);  // reference samples per node sample
    auto own = [&](int i, int j) {
        return static_cast<double>(node.heights.height(static_cast<std::size_t>(j + kBorder) * w + i + kBorder));
    };
    Reference out;
    out.lowest = std::numeric_limits<double>::max();
    out.highest = std::numeric_limits<double>::lowest();
    const auto children = synthesizer.synthesizeChildren(node.heights, where);
    for (int q = 0; q < 4; ++q) {
        const std::vector<float> fine =
            surfaceBelow(synthesizer, children[static_cast<std::size_t>(q)], childPlacement(where, q, kN), below);
        const double x0 = (q & 1) * (kN - 1) / 2.0, y0 = (q >> 1) * (kN - 1) / 2.0;
        for (int b = 0; b <= childCells; ++b) {
            for (int a = 0; a <= childCells; ++a) {
                const double x = x0 + a * step, y = y0 + b * step;
                const int i = std::min(static_cast<int>(x), kN - 2), j = std::min(static_cast<int>(y), kN - 2);
                const double surface =
                    interpolateQuad(own(i, j), own(i + 1, j), own(i, j + 1), own(i + 1, j + 1), x - i, y - j);
                const double z = fine[static_cast<std::size_t>(b + kBorder) * wc + a + kBorder];
                out.error = std::max(out.error, std::abs(z - surface));
                out.lowest = std::min(out.lowest, z);
                out.highest = std::max(out.highest, z);
            }
        }
    }
    return out;
}

/// Builds `field` at `spacing` metres with the demo's materials and the roughness measured, as prep does,
/// then walks random paths from the root kDynamicLevels levels below the static leaves, measuring every
/// static leaf and dynamic node on the way (`walks` paths). Expects every bound to hold.
void check(const std::string& name, HeightField field, double spacing, int walks)
{
    test::ScratchDir dir;
    std::vector<std::string> warnings;
    auto materials = loadDetailMaterials({std::filesystem::path(TERRAIN_MATERIALS_DIR) / "grass.mat",
                                          std::filesystem::path(TERRAIN_MATERIALS_DIR) / "rock.mat"},
                                         warnings);
    ASSERT_TRUE(materials.ok()) << materials.error().message;
    DetailSettings settings;
    settings.materials = materials.value();
    auto recipe = DetailSynthesizer::create(kN, settings);
    ASSERT_TRUE(recipe.ok());
    BuildOptions options = test::testOptions(kN, 2);
    options.spacing = spacing;
    options.leafDetailError = leafDetailErrorFunction(**recipe, true);
    options.detailDisplacementRangeFor = detailDisplacementRangeFunction(**recipe);
    const auto path = dir / "map.map";
    auto built = buildMap(std::move(field), options, path);
    ASSERT_TRUE(built.ok()) << built.error().message;
    auto map = MapFile::open(path, ReaderKind::Stream);
    ASSERT_TRUE(map.ok()) << map.error().message;
    const MapHeader& h = (*map)->header();
    ASSERT_TRUE(h.hasDetailErrors());
    auto synthesizer = DetailSynthesizer::create(kN, settingsForMap(settings, h, true));
    ASSERT_TRUE(synthesizer.ok());
    ASSERT_TRUE((*synthesizer)->settings().roughness) << "the map measured its roughness";
    TerrainNodeSource source(**map, {synthesizer->get(), 0.0});

    const int leafLevel = static_cast<int>(h.levels) - 1;
    std::map<int, std::vector<double>> ratios;  // per level: measured / bound
    int failures = 0;
    std::mt19937 random(12345);
    for (int walk = 0; walk < walks; ++walk) {
        NodePtr node = source.loadRoot().value();
        while (node->id.level < leafLevel + kDynamicLevels) {
            if (node->id.level >= leafLevel) {
                const Reference r = measure(**synthesizer, *node, source.placement(node->id));
                ratios[node->id.level].push_back(r.error / node->deltaC);
                if (r.error > node->deltaC) {
                    ++failures;
                    ADD_FAILURE() << name << ": node " << node->id.toString() << " measured " << r.error
                                  << " m against its bound " << node->deltaC << " m";
                }
                // The node's box holds what is drawn below it (culling and the selection's distance).
                EXPECT_GE(h.heightOffset + r.lowest, node->zMin) << name << ": node " << node->id.toString();
                EXPECT_LE(h.heightOffset + r.highest, node->zMax) << name << ": node " << node->id.toString();
            }
            auto children = source.loadChildren(*node);
            ASSERT_TRUE(children.ok()) << children.error().message;
            node = (*children)[random() % 4];
        }
    }
    std::printf("  %s (leaves at level %d): level, nodes, measured / bound median and largest\n", name.c_str(),
                leafLevel);
    for (auto& [level, r] : ratios) {
        std::sort(r.begin(), r.end());
        std::printf("    %2d %4zu   %.3f %.3f\n", level, r.size(), r[r.size() / 2], r.back());
    }
    EXPECT_EQ(failures, 0);
}

TEST(DetailBoundTest, BundledTerrainAt90m)
{
    auto field = readHeightField(test::demoDataPath("trinidad_co_srtm3_crop_1025.png"));
    ASSERT_TRUE(field.ok()) << field.error().message;
    check("90 m SRTM", std::move(field).value(), 90.0, 6);
}

TEST(DetailBoundTest, BundledTerrainDecimatedTo1440m)
{
    auto field = readHeightField(test::demoDataPath("trinidad_co_srtm3_crop_1025.png"));
    ASSERT_TRUE(field.ok()) << field.error().message;
    check("1440 m copy", decimate(*field, 16), 1440.0, 6);
}

TEST(DetailBoundTest, GlobalGridAt9kmUnderTheHighestMountains)
{
    auto field = readHeightField(test::testDataPath("etopo5_karakoram_129.png"));
    ASSERT_TRUE(field.ok()) << field.error().message;
    check("9 km ETOPO5", std::move(field).value(), 9000.0, 6);
}

}  // namespace
}  // namespace terrain
