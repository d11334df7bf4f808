// Leaf node error (paper 3.4.1): the stochastic estimate against an exhaustive reference (every child and
// grandchild of the leaf, measured against the leaf's surface by generic triangle interpolation) on the
// bundled real terrain, determinism, and degenerate leaves.
#include "synthesis/LeafErrorEstimator.h"

#include "MapTestSupport.h"
#include "heightfield/HeightFieldIo.h"

#include <gtest/gtest.h>

#include <bit>
#include <cstdio>
#include <thread>

namespace terrain {
namespace {

const std::filesystem::path kMaterials = TERRAIN_MATERIALS_DIR;
constexpr double kSpacing = 90.0;  // the bundled SRTM3 crop, as demos/run preps it

std::shared_ptr<const MaterialSet> grassAndRock()
{
    std::vector<std::string> warnings;
    auto set = MaterialSet::load({kMaterials / "grass.mat", kMaterials / "rock.mat"}, warnings);
    EXPECT_TRUE(set.ok()) << set.error().message;
    return std::make_shared<const MaterialSet>(std::move(set).value());
}

std::unique_ptr<const DetailSynthesizer> synthesizer(int chunkSize, std::shared_ptr<const MaterialSet> materials,
                                                     const std::string& scheme = "kobbelt")
{
    auto s = DetailSynthesizer::create(chunkSize, {scheme, 1.0, std::move(materials)});
    EXPECT_TRUE(s.ok()) << s.error().message;
    return std::move(s).value();
}

/// Placement of node (level, x, y) of `h`'s quadtree, from docs/map-format.md ("Grid and nodes").
WindowPlacement placementOf(const MapHeader& h, int level, std::int64_t x, std::int64_t y)
{
    const double spacing = h.sampleSpacing * std::pow(2.0, static_cast<double>(h.levels) - 1 - level);
    const std::int64_t cells = h.chunkSize - 1;
    return {h.originX, h.originY, h.heightOffset, spacing, x * cells - 2, y * cells - 2};
}

/// A static leaf as the viewer sees it: base heights in metres above the map's offset, and where it lies.
struct Leaf {
    NodeId id;
    DualHeightMap base;
    WindowPlacement where;
    MapHeader header;  ///< of its map
};

/// Every leaf of the trinidad map, chunk 65 (prep's default), built once for the suite.
const std::vector<Leaf>& trinidadLeaves()
{
    static const std::vector<Leaf> leaves = [] {
        test::ScratchDir dir;
        auto field = readHeightField(test::demoDataPath("trinidad_co_srtm3_crop_1025.png"));
        EXPECT_TRUE(field.ok()) << field.error().message;
        BuildOptions options;
        options.spacing = kSpacing;
        options.threads = 2;
        EXPECT_TRUE(buildMap(std::move(field).value(), options, dir / "trinidad.map").ok());
        auto map = test::openMap(dir / "trinidad.map");
        auto tree = test::decodeTree(*map);
        EXPECT_TRUE(tree.ok()) << tree.error().message;
        const MapHeader& h = map->header();
        std::vector<Leaf> out;
        for (const DirectoryEntry& e : map->directory()) {
            if (e.hasChildren) {
                continue;
            }
            Leaf leaf{e.id, {}, placementOf(h, e.id.level, e.id.x, e.id.y), h};
            const auto& codes = tree->find(e.id)->heights;
            leaf.base.size = h.windowSize();
            for (std::uint16_t code : codes) {
                leaf.base.base.push_back(static_cast<float>(h.heightStep * code));
            }
            out.push_back(std::move(leaf));
        }
        return out;
    }();
    return leaves;
}

/// The exhaustive reference: the largest |surface - leaf surface| over the N x N samples of every
/// descendant of the leaf down to `depth` dynamic levels (depth 2: all 4 children and 16 grandchildren),
/// the leaf surface interpolated by barycentric coordinates in the two template triangles of the cell
/// holding each sample (MapTestSupport.h). Placements are computed from the descendants' node ids.
double exhaustiveError(const Leaf& leaf, const DetailSynthesizer& s, int depth)
{
    const int n = s.chunkSize(), w = s.windowSize();
    DualHeightMap root = leaf.base;
    s.displace(leaf.where, nullptr, 0, root);
    auto leafAt = [&](double x, double y) {
        const int cx = std::min(static_cast<int>(x), n - 2), cy = std::min(static_cast<int>(y), n - 2);
        const auto triangles = test::templateTriangles(1, [&](int di, int dj) {
            return static_cast<double>(root.height(static_cast<std::size_t>(cy + dj + 2) * w + cx + di + 2));
        });
        return *test::heightInTriangles(triangles, x - cx, y - cy);
    };
    double worst = 0.0;
    // Node (level below the leaf, x, y) with x, y its position among the leaf's descendants of that level.
    std::function<void(const DualHeightMap&, int, std::int64_t, std::int64_t)> visit =
        [&](const DualHeightMap& parent, int level, std::int64_t x, std::int64_t y) {
            for (int q = 0; q < 4; ++q) {
                const std::int64_t cx = 2 * x + (q & 1), cy = 2 * y + (q >> 1);
                const WindowPlacement where =
                    placementOf(leaf.header, leaf.id.level + level + 1, (std::int64_t{leaf.id.x} << (level + 1)) + cx,
                                (std::int64_t{leaf.id.y} << (level + 1)) + cy);
                const DualHeightMap child = s.synthesizeChild(parent, q, where);
                const double step = std::ldexp(1.0, -(level + 1));
                for (int j = 0; j < n; ++j) {
                    for (int i = 0; i < n; ++i) {
                        const double px = (static_cast<double>(cx) * (n - 1) + i) * step;
                        const double py = (static_cast<double>(cy) * (n - 1) + j) * step;
                        const double h = child.height(static_cast<std::size_t>(j + 2) * w + i + 2);
                        worst = std::max(worst, std::abs(h - leafAt(px, py)));
                    }
                }
                if (level + 1 < depth) {
                    visit(child, level + 1, cx, cy);
                }
            }
        };
    visit(root, 0, 0, 0);
    return worst;
}

struct AccuracyCase {
    const char* name;
    const char* scheme;
    bool materials;
    double minMean;   ///< estimate / reference, mean over the leaves tested
    double minWorst;  ///< estimate / reference, the worst leaf
};

TEST(LeafErrorEstimator, EstimateComesCloseToTheExhaustiveReferenceOnRealTerrain)
{
    // Every 4th leaf of the 256 keeps the test fast; LeafErrorEstimator.h's table covers all of them.
    // Measured (mean, worst): 0.997, 0.913 with materials; 1, 1 by subdivision alone (its largest deviation
    // is always a child's); 0.913, 0.799 for Catmull-Clark, an approximating scheme whose surface keeps
    // moving with depth, so the grandchild a descent picks matters more. One descent through a random
    // child instead of all four gives 0.73, 0.08 with materials.
    constexpr std::size_t kStride = 4;
    const AccuracyCase cases[] = {
        {"grass + rock, kobbelt", "kobbelt", true, 0.98, 0.85},
        {"subdivision only, kobbelt", "kobbelt", false, 0.99, 0.95},
        {"grass + rock, catmull-clark", "catmull-clark", true, 0.88, 0.75},
    };
    const auto& leaves = trinidadLeaves();
    ASSERT_EQ(leaves.size(), 256u);
    for (const AccuracyCase& c : cases) {
        SCOPED_TRACE(c.name);
        auto s = synthesizer(65, c.materials ? grassAndRock() : nullptr, c.scheme);
        double sum = 0.0, worst = 1.0, largest = 0.0;
        std::size_t count = 0;
        for (std::size_t k = 0; k < leaves.size(); k += kStride) {
            const Leaf& leaf = leaves[k];
            const double reference = exhaustiveError(leaf, *s, 2);
            const double estimate = estimateLeafDetailError(leaf.base, leaf.where, *s, leaf.id.key());
            ASSERT_GT(reference, 0.0) << leaf.id.toString();
            // The estimate's nodes are among the reference's (depth 2): it can only find less.
            EXPECT_LE(estimate, reference * (1 + 1e-6) + 1e-5) << leaf.id.toString();
            sum += estimate / reference;
            worst = std::min(worst, estimate / reference);
            largest = std::max(largest, reference);
            ++count;
        }
        const double mean = sum / static_cast<double>(count);
        std::printf("  %s: estimate / exhaustive reference over %zu leaves: mean %.3f, worst %.3f (largest %.2f m)\n",
                    c.name, count, mean, worst, largest);
        EXPECT_GE(mean, c.minMean);
        EXPECT_GE(worst, c.minWorst);
    }
}

TEST(LeafErrorEstimator, DependsOnTheLeafAndSeedOnlyNotOnThreadsOrOrder)
{
    auto s = synthesizer(65, grassAndRock());
    const auto& leaves = trinidadLeaves();
    std::vector<float> forward;
    for (std::size_t k = 0; k < leaves.size(); k += 16) {
        forward.push_back(estimateLeafDetailError(leaves[k].base, leaves[k].where, *s, leaves[k].id.key()));
    }
    // Backwards, two threads at once, each with the other's leaves in between.
    std::vector<float> threaded(forward.size());
    auto work = [&](std::size_t first) {
        for (std::size_t i = forward.size(); i-- > 0;) {
            if (i % 2 == first) {
                const Leaf& leaf = leaves[i * 16];
                threaded[i] = estimateLeafDetailError(leaf.base, leaf.where, *s, leaf.id.key());
            }
        }
    };
    std::thread other(work, 1);
    work(0);
    other.join();
    for (std::size_t i = 0; i < forward.size(); ++i) {
        EXPECT_EQ(std::bit_cast<std::uint32_t>(threaded[i]), std::bit_cast<std::uint32_t>(forward[i]))
            << leaves[i * 16].id.toString();
    }
    // The seed picks the grandchildren: a different one may find another maximum, never a wild one.
    for (std::size_t k = 0; k < leaves.size(); k += 64) {
        const float a = estimateLeafDetailError(leaves[k].base, leaves[k].where, *s, 1);
        const float b = estimateLeafDetailError(leaves[k].base, leaves[k].where, *s, 2);
        EXPECT_NEAR(a, b, 0.2 * std::max(a, b)) << leaves[k].id.toString();
    }
}

/// A leaf whose base is the plane z = 1000 + gx * slope * spacing over the window (x east in metres).
Leaf planeLeaf(int chunkSize, double spacing, double slope)
{
    const int w = chunkSize + 4;
    Leaf leaf{
        {3, 5, 6}, {}, {612'345.0, 4'123'456.0, 0.0, spacing, 5 * (chunkSize - 1) - 2, 6 * (chunkSize - 1) - 2}, {}};
    leaf.base.size = w;
    for (int j = 0; j < w; ++j) {
        for (int i = 0; i < w; ++i) {
            leaf.base.base.push_back(
                static_cast<float>(1000.0 + static_cast<double>(leaf.where.gx0 + i) * slope * spacing));
        }
    }
    return leaf;
}

TEST(LeafErrorEstimator, PlanesAddOnlyTheDisplacement)
{
    // Every scheme reproduces a plane and the template triangles interpolate it: without materials nothing
    // is added (up to float rounding of heights near 1000 m). With them, the detail differs from the leaf's
    // surface by at most twice the displacement's bound: grass (0.8 m) on flat ground, rock (3 m) on steep.
    struct Case {
        const char* what;
        const char* scheme;
        bool materials;
        double slope;  ///< rise per metre
        double above;  ///< the estimate exceeds this
        double below;  ///< and stays under this
    };
    const Case cases[] = {
        {"flat, subdivision only, kobbelt", "kobbelt", false, 0.0, -1.0, 1e-3},
        {"tilted, subdivision only, kobbelt", "kobbelt", false, 0.3, -1.0, 1e-3},
        {"tilted, subdivision only, bilinear", "bilinear", false, 0.3, -1.0, 1e-3},
        {"tilted, subdivision only, catmull-clark", "catmull-clark", false, 0.3, -1.0, 1e-3},
        {"flat, grass + rock: grass", "kobbelt", true, 0.0, 0.05, 2 * 0.8 + 1e-3},
        {"45 degrees, grass + rock: rock", "kobbelt", true, 1.0, 0.2, 2 * 3.0 + 1e-3},
    };
    for (const Case& c : cases) {
        auto s = synthesizer(17, c.materials ? grassAndRock() : nullptr, c.scheme);
        const Leaf leaf = planeLeaf(17, 8.0, c.slope);
        const float e = estimateLeafDetailError(leaf.base, leaf.where, *s, 42);
        EXPECT_GT(e, c.above) << c.what;
        EXPECT_LT(e, c.below) << c.what;
    }
}

TEST(LeafErrorEstimator, ChildPlacementIsTheChildNodesPlacement)
{
    struct Case {
        int level;
        std::int64_t x, y;
        int chunkSize;
    };
    const Case cases[] = {{0, 0, 0, 65}, {3, 5, 6, 65}, {4, 15, 0, 17}, {6, 63, 63, 3}};
    for (const Case& c : cases) {
        const std::int64_t cells = c.chunkSize - 1;
        const double spacing = std::ldexp(90.0, -c.level);
        const WindowPlacement parent{612'345.0, 4'123'456.0, 1500.0, spacing, c.x * cells - 2, c.y * cells - 2};
        for (int q = 0; q < 4; ++q) {
            const WindowPlacement child = childPlacement(parent, q, c.chunkSize);
            EXPECT_EQ(child.spacing, spacing / 2);
            EXPECT_EQ(child.gx0, (2 * c.x + (q & 1)) * cells - 2) << c.level << "/" << c.x << "/" << c.y << " q" << q;
            EXPECT_EQ(child.gy0, (2 * c.y + (q >> 1)) * cells - 2) << c.level << "/" << c.x << "/" << c.y << " q" << q;
            EXPECT_EQ(child.originX, parent.originX);
            EXPECT_EQ(child.originY, parent.originY);
            EXPECT_EQ(child.heightOffset, parent.heightOffset);
        }
    }
}

TEST(LeafErrorEstimator, WindowPlacementIsTheMapFormatsPlacement)
{
    // windowPlacement is what the viewer and prep's estimate (leafDetailErrorFunction) both place nodes with.
    MapHeader h;
    h.chunkSize = 17;
    h.levels = 5;
    h.sampleSpacing = 2.5;
    h.originX = 612'345.0;
    h.originY = 4'123'456.0;
    h.heightOffset = -120.0;
    const NodeId ids[] = {NodeId::root(), {1, 1, 0}, {3, 5, 6}, {4, 15, 15}, {7, 100, 3}};
    for (const NodeId& id : ids) {
        const WindowPlacement expected = placementOf(h, id.level, id.x, id.y);
        const WindowPlacement where = windowPlacement(h, id);
        EXPECT_EQ(where.originX, expected.originX) << id.toString();
        EXPECT_EQ(where.originY, expected.originY) << id.toString();
        EXPECT_EQ(where.heightOffset, expected.heightOffset) << id.toString();
        EXPECT_EQ(where.spacing, expected.spacing) << id.toString();
        EXPECT_EQ(where.gx0, expected.gx0) << id.toString();
        EXPECT_EQ(where.gy0, expected.gy0) << id.toString();
    }
}

}  // namespace
}  // namespace terrain
