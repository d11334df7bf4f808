// DepthOcclusion and hiddenFrom (issue 16): boxes against last frame's depth, and the selection's question
// from pixel counts and depth together. The depth buffers are made here from the GL's depth formula for a
// wall at a known eye distance, independently of the camera matrices the code under test uses; the
// random check projects points with the camera's own basis vectors (forward, right, up), not its matrices.
#include "lod/DepthOcclusion.h"
#include "lod/NodeVisibility.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <unordered_map>
#include <vector>

namespace terrain {
namespace {

constexpr int kWidth = 160, kHeight = 90;
constexpr double kWallDistance = 100.0;
constexpr int kWallRows = 56;  ///< rows 0 (bottom) to 55 hold the wall; a tile boundary (7 x 8)

Camera wallCamera()
{
    Camera camera;
    camera.position = {384.0, 0.0, 0.0};
    camera.yaw = 0.0;  // looking north, +y
    camera.pitch = 0.0;
    camera.viewportWidth = kWidth;
    camera.viewportHeight = kHeight;
    camera.nearPlane = 1.0;
    camera.farPlane = 10000.0;
    return camera;
}

/// OpenGL's window depth (depth range [0, 1]) of a point at eye distance `d`.
double windowDepth(const Camera& c, double d)
{
    const double n = c.nearPlane, f = c.farPlane;
    const double ndc = (f + n) / (f - n) - 2.0 * f * n / ((f - n) * d);
    return 0.5 * ndc + 0.5;
}

/// A wall facing the camera at kWallDistance over the bottom kWallRows rows, nothing (depth 1) above.
std::vector<float> wallDepth(const Camera& camera)
{
    std::vector<float> depth(static_cast<std::size_t>(kWidth) * kHeight, 1.0f);
    for (int y = 0; y < kWallRows; ++y) {
        for (int x = 0; x < kWidth; ++x) {
            depth[static_cast<std::size_t>(y) * kWidth + x] = static_cast<float>(windowDepth(camera, kWallDistance));
        }
    }
    return depth;
}

Aabb box(double x0, double y0, double z0, double x1, double y1, double z1)
{
    return Aabb{{x0, y0, z0}, {x1, y1, z1}};
}

TEST(DepthOcclusionTest, BoxesWhollyBehindTheWallAreOccludedAndNoOthers)
{
    const Camera camera = wallCamera();
    const DepthOcclusion occlusion(wallDepth(camera), kWidth, kHeight, camera);
    // Row of a point (eye depth y, height z): 45 + z / y / tan(30 deg) * 45; the wall's top is row 55.
    EXPECT_TRUE(occlusion.occluded(box(360, 200, -50, 400, 300, -5))) << "behind, below the wall's top";
    EXPECT_FALSE(occlusion.occluded(box(360, 200, -50, 400, 300, 40))) << "its top shows above the wall";
    EXPECT_FALSE(occlusion.occluded(box(380, 20, -10, 390, 30, -5))) << "in front of the wall";
    EXPECT_FALSE(occlusion.occluded(box(380, 80, -10, 390, 150, -5))) << "through the wall: its near part shows";
    EXPECT_FALSE(occlusion.occluded(box(370, -5, -10, 400, 300, -5))) << "reaches behind the near plane";
    EXPECT_TRUE(occlusion.occluded(box(-2000, 200, -50, 400, 300, -5)))
        << "what lies outside the image was not in view; the rest is behind the wall";
    EXPECT_FALSE(occlusion.occluded(box(3000, 200, -50, 3100, 300, -5))) << "wholly out of view";
    // Grown by the viewer's motion: a box just under the wall's top is hidden from here, not from 20 m on.
    EXPECT_TRUE(occlusion.occluded(box(360, 200, -50, 400, 300, 10)));
    EXPECT_FALSE(occlusion.occluded(box(360, 200, -50, 400, 300, 10), 20.0));
    EXPECT_TRUE(occlusion.occluded(box(360, 200, -50, 400, 300, -5), 5.0)) << "well below it, still hidden";
    EXPECT_EQ(occlusion.eye(), camera.position);
    // A gap in the wall, one tile wide, where the box lies: seen through it.
    auto gap = wallDepth(camera);
    const double column = 80.0;  // the box's centre projects to the image's centre column
    for (int y = 0; y < kWallRows; ++y) {
        for (int x = 80; x < 88; ++x) {
            gap[static_cast<std::size_t>(y) * kWidth + x] = 1.0f;
        }
    }
    const DepthOcclusion throughGap(gap, kWidth, kHeight, camera);
    EXPECT_FALSE(throughGap.occluded(box(382, 200, -50, 386, 300, -5))) << column;
    EXPECT_TRUE(throughGap.occluded(box(300, 200, -50, 330, 300, -5))) << "left of the gap";
}

TEST(DepthOcclusionTest, EveryPointOfAnOccludedBoxIsBehindTheDepthDrawnAtItsPixel)
{
    const Camera camera = wallCamera();
    // A wall with random gaps: one column in 40 open.
    auto depth = wallDepth(camera);
    std::mt19937 random(7);
    for (int x = 0; x < kWidth; ++x) {
        if (random() % 40 == 0) {
            for (int y = 0; y < kWallRows; ++y) {
                depth[static_cast<std::size_t>(y) * kWidth + x] = 1.0f;
            }
        }
    }
    const DepthOcclusion occlusion(depth, kWidth, kHeight, camera);
    const glm::dvec3 forward = camera.forward(), right = camera.right(), up = camera.up();
    const double t = std::tan(camera.verticalFov / 2.0);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    int occludedBoxes = 0, visibleBoxes = 0;
    for (int trial = 0; trial < 2000; ++trial) {
        const double x = 384.0 + (u(random) - 0.5) * 600.0, y = 20.0 + u(random) * 400.0, z = -80.0 + u(random) * 90;
        const Aabb b = box(x, y, z, x + u(random) * 60.0, y + u(random) * 60.0, z + u(random) * 30.0);
        if (!occlusion.occluded(b)) {
            ++visibleBoxes;
            continue;
        }
        ++occludedBoxes;
        for (int s = 0; s < 200; ++s) {
            const glm::dvec3 p = b.lo + (b.hi - b.lo) * glm::dvec3(u(random), u(random), u(random));
            const glm::dvec3 v = p - camera.position;
            const double d = glm::dot(v, forward);
            ASSERT_GT(d, camera.nearPlane);
            const double px = (glm::dot(v, right) / (d * t * camera.aspect()) * 0.5 + 0.5) * kWidth;
            const double py = (glm::dot(v, up) / (d * t) * 0.5 + 0.5) * kHeight;
            if (px < 0 || py < 0 || px >= kWidth || py >= kHeight) {
                continue;  // out of the frame's view
            }
            const float drawn = depth[static_cast<std::size_t>(py) * kWidth + static_cast<std::size_t>(px)];
            EXPECT_LT(drawn, windowDepth(camera, d)) << "trial " << trial << ": a point of an occluded box shows";
        }
    }
    EXPECT_GT(occludedBoxes, 200);
    EXPECT_GT(visibleBoxes, 200);
}

TEST(DepthOcclusionTest, APointShowsOnOrInFrontOfTheDepthAndNotBehindIt)
{
    const Camera camera = wallCamera();
    const DepthSurface surface(wallDepth(camera), kWidth, kHeight, camera);
    // Eye distance is y here (camera at y = 0 looking north); the wall covers rows below the horizon's 10
    // rows above the centre.
    EXPECT_TRUE(surface.shows({384.0, 100.0, -10.0})) << "on the wall";
    EXPECT_TRUE(surface.shows({384.0, 101.5, -10.0})) << "within the 2% slack";
    EXPECT_FALSE(surface.shows({384.0, 103.0, -10.0})) << "just behind it";
    EXPECT_FALSE(surface.shows({384.0, 300.0, -30.0})) << "far behind it";
    EXPECT_TRUE(surface.shows({384.0, 50.0, -10.0})) << "in front of it";
    EXPECT_TRUE(surface.shows({384.0, 300.0, 100.0})) << "above the wall, against nothing";
    EXPECT_FALSE(surface.shows({5000.0, 300.0, -30.0})) << "out of the image";
    EXPECT_FALSE(surface.shows({384.0, -10.0, 0.0})) << "behind the camera";
    EXPECT_FALSE(surface.shows({384.0, 103.0, -10.0}, 0.0));
    EXPECT_TRUE(surface.shows({384.0, 103.0, -10.0}, 0.05)) << "a larger slack";
}

/// Nodes of a 1024 m square by key, each with its box heights.
class BoxTree final : public LodTree {
public:
    QuadtreeExtent extent() const override { return {0.0, 0.0, 1024.0}; }
    NodeInfo info(const NodeId& id) const override { return nodes.at(id.key()); }
    void add(const NodeId& id, double zMin, double zMax, bool hasChildren)
    {
        nodes[id.key()] = NodeInfo{hasChildren, 1.0f, zMin, zMax};
    }
    std::unordered_map<std::uint64_t, NodeInfo> nodes;
};

TEST(DepthOcclusionTest, ADarkNodeIsHiddenOnlyWhereItsBoxesAreBehindTheDepth)
{
    const Camera camera = wallCamera();
    const DepthOcclusion occlusion(wallDepth(camera), kWidth, kHeight, camera);
    // Node (2, 1, 1): x, y in [256, 512], behind the wall. Its box's near top edge at 40 m shows over the wall
    // (row 57); its children's boxes do not: the near two are low, the far two as high but farther.
    const NodeId node{2, 1, 1};
    BoxTree tree;
    tree.add(node, -200.0, 40.0, true);
    for (int q = 0; q < 4; ++q) {
        const bool far = node.child(q).y % 2 == 1;
        tree.add(node.child(q), -200.0, far ? 40.0 : 5.0, true);
    }
    const NodeId low{2, 0, 1};  // x in [0, 256]: its box is behind the wall as a whole
    tree.add(low, -300.0, -20.0, true);
    const NodeId unseen{2, 2, 1};  // never drawn
    tree.add(unseen, -300.0, -20.0, false);

    NodeVisibility counts(2);
    const std::vector<NodeId> drawn{node, low};
    for (std::uint64_t f = 1; f <= 2; ++f) {
        counts.record(f, drawn, std::vector<std::uint32_t>{0, 0});
    }
    ASSERT_EQ(counts.seen(node), NodeVisibility::Seen::kHidden);

    bool resident = false;
    const auto hidden = hiddenFrom(counts, &occlusion, tree, [&](const NodeId&) { return resident; });
    EXPECT_FALSE(hidden(node)) << "dark, but its box shows and its children are not resident";
    EXPECT_TRUE(hidden(low)) << "dark and its box behind the wall";
    EXPECT_TRUE(hidden(unseen)) << "never measured, and behind the wall";
    resident = true;
    EXPECT_TRUE(hidden(node)) << "every child's box is behind the wall";
    EXPECT_FALSE(hiddenFrom(
        counts, &occlusion, tree, [&](const NodeId& id) { return id.key() == node.key(); }, 30.0)(node))
        << "grown by 30 m, the far children's tops show over the wall";
    tree.add(node.child(3), -200.0, 90.0, false);  // a peak in one far quarter shows over the wall
    EXPECT_FALSE(hidden(node));

    EXPECT_TRUE(hiddenFrom(counts, nullptr, tree)(node)) << "without depth the counts decide";
    EXPECT_FALSE(hiddenFrom(counts, nullptr, tree)(unseen)) << "without depth an unmeasured node is not hidden";
    counts.record(3, drawn, std::vector<std::uint32_t>{0, 4});
    EXPECT_FALSE(hidden(low)) << "counted pixels: visible, whatever the depth says";
}

}  // namespace
}  // namespace terrain
