// Dynamic node synthesis (paper 3.4.3, 4.2.4): a child's even samples are its parent's (base and
// displacement), neighbouring nodes agree bit for bit on every sample they share at every depth (dynamic
// next to dynamic, and a static node next to the dynamic children of its neighbour), the displacement is
// the materials' at each sample's world position, and textures upsample with shared edge texels.
#include "synthesis/DetailSynthesizer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>

namespace terrain {
namespace {

const std::filesystem::path kMaterials = TERRAIN_MATERIALS_DIR;
constexpr int kN = 17;  // small chunks keep the test fast; the rules do not depend on N
constexpr int kW = kN + 2 * kBorder;
constexpr double kRootSpacing = 64.0;
constexpr double kOriginX = 612'345.0;  // hundreds of km from the origin, as real maps are
constexpr double kOriginY = 4'123'456.0;

std::shared_ptr<const MaterialSet> grassAndRock()
{
    std::vector<std::string> warnings;
    auto set = MaterialSet::load({kMaterials / "grass.mat", kMaterials / "rock.mat"}, warnings);
    EXPECT_TRUE(set.ok()) << set.error().message;
    return std::make_shared<const MaterialSet>(std::move(set).value());
}

std::unique_ptr<const DetailSynthesizer> synthesizer(std::shared_ptr<const MaterialSet> materials,
                                                     std::string scheme = "kobbelt")
{
    auto s = DetailSynthesizer::create(kN, {std::move(scheme), 1.0, std::move(materials)});
    EXPECT_TRUE(s.ok()) << s.error().message;
    return std::move(s).value();
}

/// Node (level, x, y) of a quadtree whose level 0 is a row of "static" nodes side by side.
struct Node {
    int level;
    std::int64_t x, y;
    bool operator<(const Node& o) const { return std::tie(level, x, y) < std::tie(o.level, o.x, o.y); }
};

WindowPlacement placementOf(const Node& node)
{
    const double spacing = std::ldexp(kRootSpacing, -node.level);
    return {kOriginX, kOriginY, 1000.0, spacing, node.x * (kN - 1) - kBorder, node.y * (kN - 1) - kBorder};
}

/// Steep hills: slopes from flat to well past the rock material's 30 degrees, so both materials and their
/// blend appear.
double terrainHeight(double x, double y)
{
    return 300.0 * std::sin(x / 700.0) * std::cos(y / 500.0) + 80.0 * std::sin(x / 90.0 + y / 130.0);
}

/// Synthesizes nodes on demand: level-0 nodes are static (their base sampled from terrainHeight and
/// displaced without a parent), deeper ones dynamic children of their parent.
class Tree {
public:
    explicit Tree(const DetailSynthesizer& s) : mS(s) {}

    const DualHeightMap& node(const Node& n)
    {
        auto it = mNodes.find(n);
        if (it != mNodes.end()) {
            return it->second;
        }
        DualHeightMap map;
        if (n.level == 0) {
            const WindowPlacement where = placementOf(n);
            map.size = kW;
            map.base.resize(kW * kW);
            for (int j = 0; j < kW; ++j) {
                for (int i = 0; i < kW; ++i) {
                    map.base[j * kW + i] =
                        static_cast<float>(terrainHeight(static_cast<double>(where.gx0 + i) * where.spacing,
                                                         static_cast<double>(where.gy0 + j) * where.spacing));
                }
            }
            mS.displace(where, nullptr, 0, map);
        } else {
            const Node parent{n.level - 1, n.x >> 1, n.y >> 1};
            const int quadrant = static_cast<int>((n.x & 1) | ((n.y & 1) << 1));
            map = mS.synthesizeChild(node(parent), quadrant, placementOf(n));
        }
        return mNodes.emplace(n, std::move(map)).first->second;
    }

private:
    const DetailSynthesizer& mS;
    std::map<Node, DualHeightMap> mNodes;
};

float surfaceAt(const DualHeightMap& map, int i, int j)
{
    return map.height(static_cast<std::size_t>(j + kBorder) * kW + i + kBorder);
}

bool bitEqual(float a, float b)
{
    return std::memcmp(&a, &b, sizeof a) == 0;
}

TEST(DetailSynthesizer, ChildEvenSamplesAreTheParentsSamplesBaseAndDisplacement)
{
    auto s = synthesizer(grassAndRock());
    Tree tree(*s);
    for (int level = 1; level <= 4; ++level) {
        const Node child{level, 5, 3};  // some node below level-0 node (0, 0)... and its ancestors
        const Node parent{level - 1, child.x >> 1, child.y >> 1};
        const DualHeightMap& c = tree.node(child);
        const DualHeightMap& p = tree.node(parent);
        const int px0 = 1 + static_cast<int>(child.x & 1) * (kN - 1) / 2;
        const int py0 = 1 + static_cast<int>(child.y & 1) * (kN - 1) / 2;
        int mismatches = 0;
        for (int j = 0; j < kW; j += 2) {
            for (int i = 0; i < kW; i += 2) {
                const std::size_t k = static_cast<std::size_t>(j) * kW + i;
                const std::size_t pk = static_cast<std::size_t>(py0 + j / 2) * kW + px0 + i / 2;
                mismatches += !bitEqual(c.base[k], p.base[pk]) || !bitEqual(c.displacement[k], p.displacement[pk]);
            }
        }
        EXPECT_EQ(mismatches, 0) << "level " << level;
    }
}

TEST(DetailSynthesizer, NeighboursShareBitIdenticalEdgesAtEveryDepth)
{
    for (bool withMaterials : {false, true}) {
        auto s = synthesizer(withMaterials ? grassAndRock() : nullptr);
        Tree tree(*s);
        int compared = 0, mismatches = 0;
        // Level-0 nodes (0, 0) and (1, 0) are "static" neighbours; below them dynamic nodes meet across the
        // line x = one root node, and across internal lines.
        for (int level = 0; level <= 4; ++level) {
            const std::int64_t cells = std::int64_t{1} << level;
            for (std::int64_t y = 0; y < cells; y += std::max<std::int64_t>(1, cells / 3)) {
                for (std::int64_t x = cells / 2; x <= cells; x += std::max<std::int64_t>(1, cells / 2)) {
                    // West node (x - 1, y) and east node (x, y) share the west node's east edge.
                    const DualHeightMap& west = tree.node({level, x - 1 + (level == 0 ? 1 : 0), y});
                    const DualHeightMap& east = tree.node({level, x + (level == 0 ? 1 : 0), y});
                    for (int j = 0; j < kN; ++j) {
                        ++compared;
                        mismatches += !bitEqual(surfaceAt(west, kN - 1, j), surfaceAt(east, 0, j));
                    }
                }
            }
        }
        EXPECT_GT(compared, 100);
        EXPECT_EQ(mismatches, 0) << (withMaterials ? "with materials" : "subdivision only");
    }
}

TEST(DetailSynthesizer, StaticNodeMeetsTheDynamicChildrenOfItsNeighbourExactly)
{
    // A static leaf (level-0 node 0) next to a finer dynamic node below its neighbour (level-0 node 1):
    // along the shared edge, at the leaf's samples, the surfaces are the same bits (skirts cover only the
    // T-junctions between them).
    auto s = synthesizer(grassAndRock());
    Tree tree(*s);
    const DualHeightMap& leaf = tree.node({0, 0, 0});
    for (int level = 1; level <= 3; ++level) {
        const std::int64_t scale = std::int64_t{1} << level;
        for (std::int64_t y = 0; y < scale; ++y) {
            const DualHeightMap& fine = tree.node({level, scale, y});  // west column below node 1
            for (int j = 0; j < kN; j += static_cast<int>(scale)) {
                const int leafJ = static_cast<int>((y * (kN - 1) + j) / scale);
                if ((y * (kN - 1) + j) % scale != 0) {
                    continue;
                }
                EXPECT_TRUE(bitEqual(surfaceAt(fine, 0, j), surfaceAt(leaf, kN - 1, leafJ)))
                    << "level " << level << " y " << y << " j " << j;
            }
        }
    }
}

TEST(DetailSynthesizer, PlacementSlopesAreMeasuredOnStaticNodesAndInterpolatedBelow)
{
    // Issue 12: a dynamic child's placement slopes are its parent's, interpolated (even samples copy, odd
    // ones average their two or four neighbours), so below a static node every sample keeps one material
    // weighting at every depth; a node displaced without a parent measures its own base.
    auto s = synthesizer(grassAndRock());
    Tree tree(*s);
    const DualHeightMap& root = tree.node({0, 0, 0});
    ASSERT_EQ(root.slope.size(), root.base.size());
    const WindowPlacement rootWhere = placementOf({0, 0, 0});
    for (int j = 1; j < kW - 1; j += 5) {
        for (int i = 1; i < kW - 1; i += 3) {
            EXPECT_EQ(root.slope[static_cast<std::size_t>(j) * kW + i],
                      static_cast<float>(s->slopeDegrees(root, i, j, rootWhere.spacing)));
        }
    }
    double spread = 0.0;
    for (int level = 1; level <= 3; ++level) {
        const Node child{level, 5, 3};
        const Node parent{level - 1, child.x >> 1, child.y >> 1};
        const DualHeightMap& c = tree.node(child);
        const DualHeightMap& p = tree.node(parent);
        const int px0 = 1 + static_cast<int>(child.x & 1) * (kN - 1) / 2;
        const int py0 = 1 + static_cast<int>(child.y & 1) * (kN - 1) / 2;
        auto parentAt = [&](double u, double v) {  // bilinear in the parent's window
            const int i0 = static_cast<int>(std::floor(u)), j0 = static_cast<int>(std::floor(v));
            const double fu = u - i0, fv = v - j0;
            auto at = [&](int i, int j) { return static_cast<double>(p.slope[static_cast<std::size_t>(j) * kW + i]); };
            return (1 - fv) * ((1 - fu) * at(i0, j0) + fu * at(std::min(i0 + 1, kW - 1), j0)) +
                   fv * ((1 - fu) * at(i0, std::min(j0 + 1, kW - 1)) +
                         fu * at(std::min(i0 + 1, kW - 1), std::min(j0 + 1, kW - 1)));
        };
        for (int j = 0; j < kW - 1; ++j) {
            for (int i = 0; i < kW - 1; ++i) {
                const double expected = parentAt(px0 + i / 2.0, py0 + j / 2.0);
                const float got = c.slope[static_cast<std::size_t>(j) * kW + i];
                EXPECT_NEAR(got, expected, 1e-4) << "level " << level << " (" << i << ", " << j << ")";
                if (i > 0 && j > 0) {
                    spread = std::max(spread, std::abs(s->slopeDegrees(c, i, j, placementOf(child).spacing) - got));
                }
            }
        }
    }
    EXPECT_GT(spread, 0.0) << "the node's own slopes differ from the placement it inherits";
}

TEST(DetailSynthesizer, DisplacementIsTheMaterialsAtEachNewSamplesWorldPosition)
{
    auto materials = grassAndRock();
    auto s = synthesizer(materials);
    Tree tree(*s);
    const Node child{3, 9, 2};
    const DualHeightMap& map = tree.node(child);
    const WindowPlacement where = placementOf(child);
    int checked = 0;
    for (int j = 1; j < kW - 1; j += 3) {
        for (int i = 1; i < kW - 1; i += 2) {
            if (i % 2 == 0 && j % 2 == 0) {
                continue;  // copied from the parent (checked above)
            }
            const std::size_t k = static_cast<std::size_t>(j) * kW + i;
            const float slope = map.slope[k];  // the placement slope (checked below)
            const float height = static_cast<float>(where.heightOffset + map.base[k]);
            const float expected = materials->displacement(where.grid(kW).x(i), where.grid(kW).y(j), slope, height);
            EXPECT_TRUE(bitEqual(map.displacement[k], expected)) << i << ", " << j;
            ++checked;
        }
    }
    EXPECT_GT(checked, 50);
}

/// Grass and rock (rock blended by height) and a third material in hollows, whose edge wanders.
std::shared_ptr<const MaterialSet> coverMaterials()
{
    std::vector<std::string> warnings;
    auto set = MaterialSet::load({kMaterials / "grass.mat", kMaterials / "rock.mat"}, warnings);
    EXPECT_TRUE(set.ok()) << set.error().message;
    std::vector<Material> materials = set->materials();
    auto config = ConfigFile::parse(
        "name = scree\ndisplacement = fbm\namplitude = 0.5\nwavelength = 20\ncurvature = 0.5, 90\n"
        "curvature_blend = 1\nvariation = 1, 300\nblend_height = 1\n",
        "scree.mat");
    EXPECT_TRUE(config.ok());
    auto scree = parseMaterial(*config, warnings);
    EXPECT_TRUE(scree.ok()) << scree.error().message;
    materials.push_back(std::move(scree).value());
    return std::make_shared<const MaterialSet>(std::move(materials));
}

TEST(DetailSynthesizer, CurvaturesAndShownWeightsNestLikeTheSlopes)
{
    auto materials = coverMaterials();
    auto s = synthesizer(materials);
    Tree tree(*s);
    int differing = 0, hollows = 0;
    for (int level = 1; level <= 3; ++level) {
        const Node child{level, 5, 3};
        const Node parent{level - 1, child.x >> 1, child.y >> 1};
        const DualHeightMap& c = tree.node(child);
        const DualHeightMap& p = tree.node(parent);
        ASSERT_EQ(c.curvature.size(), c.base.size());
        ASSERT_EQ(c.weights.size(), c.base.size() * 4);
        const int px0 = 1 + static_cast<int>(child.x & 1) * (kN - 1) / 2;
        const int py0 = 1 + static_cast<int>(child.y & 1) * (kN - 1) / 2;
        auto parentCurvature = [&](int i, int j) { return p.curvature[static_cast<std::size_t>(j) * kW + i]; };
        for (int j = 0; j + 1 < kW; ++j) {
            for (int i = 0; i + 1 < kW; ++i) {
                const std::size_t k = static_cast<std::size_t>(j) * kW + i;
                const int pi = px0 + i / 2, pj = py0 + j / 2;
                float expected = parentCurvature(pi, pj);
                if (i % 2 == 1 && j % 2 == 0) {
                    expected = 0.5f * (parentCurvature(pi, pj) + parentCurvature(pi + 1, pj));
                } else if (i % 2 == 0 && j % 2 == 1) {
                    expected = 0.5f * (parentCurvature(pi, pj) + parentCurvature(pi, pj + 1));
                } else if (i % 2 == 1) {
                    expected = 0.25f * ((parentCurvature(pi, pj) + parentCurvature(pi + 1, pj)) +
                                        (parentCurvature(pi, pj + 1) + parentCurvature(pi + 1, pj + 1)));
                }
                EXPECT_TRUE(bitEqual(c.curvature[k], expected)) << level << ": " << i << ", " << j;
                if (i % 2 == 0 && j % 2 == 0) {
                    const std::size_t q = static_cast<std::size_t>(pj) * kW + pi;
                    for (int m = 0; m < 4; ++m) {
                        EXPECT_EQ(c.weights[4 * k + m], p.weights[4 * q + m]) << level << ": " << i << ", " << j;
                    }
                }
                hollows += c.weights[4 * k + 2] > 0;
            }
        }
        const auto shown = s->materialWeights(c);
        const auto smooth = s->displacementWeights(c, placementOf(child));
        ASSERT_EQ(shown.size(), smooth.size());
        for (std::size_t k = 0; k < shown.size(); k += 4) {
            EXPECT_NEAR(shown[k] + shown[k + 1] + shown[k + 2], 255, 2);
            differing += shown[k] != smooth[k];
        }
    }
    EXPECT_GT(hollows, 100);   // the third material is placed somewhere
    EXPECT_GT(differing, 20);  // and height blending moves what the ground shows
}

TEST(DetailSynthesizer, SubdivisionOnlyHasNoDisplacementAndNoWeights)
{
    auto s = synthesizer(nullptr);
    Tree tree(*s);
    const DualHeightMap& map = tree.node({2, 1, 1});
    EXPECT_FALSE(map.hasDisplacement());
    EXPECT_TRUE(s->materialWeights(map).empty());
}

TEST(DetailSynthesizer, MaterialWeightsCoverSteepAndGentleGroundAndSumToOne)
{
    auto s = synthesizer(grassAndRock());
    Tree tree(*s);
    bool sawGrass = false, sawRock = false;
    for (std::int64_t x = 0; x < 4; ++x) {
        const Node n{2, x, 1};
        const auto weights = s->materialWeights(tree.node(n));
        ASSERT_EQ(weights.size(), static_cast<std::size_t>(kN) * kN * 4);
        for (std::size_t k = 0; k < weights.size(); k += 4) {
            EXPECT_NEAR(weights[k] + weights[k + 1], 255, 1);
            EXPECT_EQ(weights[k + 2], 0);
            sawGrass |= weights[k] == 255;
            sawRock |= weights[k + 1] == 255;
        }
    }
    EXPECT_TRUE(sawGrass);
    EXPECT_TRUE(sawRock);
}

TEST(DetailSynthesizer, ErrorsNameTheOption)
{
    auto scheme = DetailSynthesizer::create(kN, {"loop", 1.0, nullptr});
    ASSERT_FALSE(scheme.ok());
    EXPECT_NE(scheme.error().message.find("detail_subdivision_scheme"), std::string::npos) << scheme.error().message;
    auto omega = DetailSynthesizer::create(kN, {"kobbelt", 3.0, nullptr});
    ASSERT_FALSE(omega.ok());
    EXPECT_NE(omega.error().message.find("detail_subdivision_factor"), std::string::npos) << omega.error().message;
}

TEST(DetailSynthesizer, UpsampledTexturesShareEdgeTexelsAndKeepTheParents)
{
    constexpr int t = 9;
    std::vector<std::uint8_t> parent(t * t * 3);
    for (std::size_t k = 0; k < parent.size(); ++k) {
        parent[k] = static_cast<std::uint8_t>((k * 37) % 251);
    }
    const auto sw = upsampleTexture(parent, t, 0), se = upsampleTexture(parent, t, 1);
    const auto nw = upsampleTexture(parent, t, 2);
    auto texel = [&](const std::vector<std::uint8_t>& tex, int i, int j, int c) { return tex[(j * t + i) * 3 + c]; };
    for (int j = 0; j < t; ++j) {
        for (int c = 0; c < 3; ++c) {
            EXPECT_EQ(texel(sw, t - 1, j, c), texel(se, 0, j, c));  // shared vertical edge
            EXPECT_EQ(texel(sw, j, t - 1, c), texel(nw, j, 0, c));  // shared horizontal edge
        }
    }
    // Even texels are the parent's texels.
    for (int j = 0; j < t; j += 2) {
        for (int i = 0; i < t; i += 2) {
            EXPECT_EQ(texel(se, i, j, 1), texel(parent, (t - 1) / 2 + i / 2, j / 2, 1));
        }
    }
}

}  // namespace
}  // namespace terrain
