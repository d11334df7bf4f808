#include "gpudata/NodeVertexData.h"

#include "quadtree/TemplateTriangulation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

namespace terrain {
namespace {

constexpr int kN = 17;
constexpr int kW = kN + 4;

std::vector<std::uint16_t> window(const std::function<double(int, int)>& height)
{
    std::vector<std::uint16_t> codes(kW * kW);
    for (int j = -2; j < kN + 2; ++j) {
        for (int i = -2; i < kN + 2; ++i) {
            codes[static_cast<std::size_t>(j + 2) * kW + i + 2] = static_cast<std::uint16_t>(std::lround(height(i, j)));
        }
    }
    return codes;
}

/// The surface window in metres for codes of `step` metres each.
std::vector<float> metres(const std::vector<std::uint16_t>& codes, double step)
{
    std::vector<float> out(codes.size());
    for (std::size_t k = 0; k < codes.size(); ++k) {
        out[k] = static_cast<float>(codes[k] * step);
    }
    return out;
}

TEST(NodeVertexDataTest, MaterialWeightsFollowTheirSampleAndDefaultToZero)
{
    std::vector<std::uint16_t> codes = window([](int i, int j) { return 1000 + i + j; });
    std::vector<std::uint8_t> weights(static_cast<std::size_t>(kN) * kN * 4);
    for (std::size_t k = 0; k < weights.size(); ++k) {
        weights[k] = static_cast<std::uint8_t>(k * 7 % 256);
    }
    const TemplateMesh mesh = buildTemplateMesh(kN);
    const auto with = buildNodeVertices(mesh, metres(codes, 1.0), 1.0, weights);
    const auto without = buildNodeVertices(mesh, metres(codes, 1.0), 1.0, {});
    for (std::size_t k = 0; k < mesh.vertices.size(); ++k) {
        const int i = mesh.vertices[k].i, j = mesh.vertices[k].j;
        for (int m = 0; m < 4; ++m) {
            EXPECT_EQ(with[k].materialWeights[m], weights[(static_cast<std::size_t>(j) * kN + i) * 4 + m]);
            EXPECT_EQ(without[k].materialWeights[m], 0);
        }
    }
}

TEST(NodeVertexDataTest, ParentSurfaceFollowsTheParentsTriangles)
{
    std::mt19937 random(3);
    std::uniform_int_distribution<int> code(1000, 3000);
    std::vector<std::uint16_t> codes = window([&](int, int) { return code(random); });
    const TemplateMesh mesh = buildTemplateMesh(kN);
    const auto vertices = buildNodeVertices(mesh, metres(codes, 0.5), 10.0, {});
    ASSERT_EQ(vertices.size(), mesh.vertices.size());
    auto at = [&](int i, int j) -> double { return codes[static_cast<std::size_t>(j + 2) * kW + i + 2]; };
    for (std::size_t k = 0; k < mesh.vertices.size(); ++k) {
        const int i = mesh.vertices[k].i, j = mesh.vertices[k].j;
        // The parent's samples are the even ones; evaluate its triangulated surface at (i, j) by the
        // generic quad interpolation, independent of which neighbours the implementation averages.
        const int pi = std::min(i / 2, (kN - 1) / 2 - 1), pj = std::min(j / 2, (kN - 1) / 2 - 1);
        const double fx = (i - 2 * pi) / 2.0, fy = (j - 2 * pj) / 2.0;
        const double expected = interpolateQuad(at(2 * pi, 2 * pj), at(2 * pi + 2, 2 * pj), at(2 * pi, 2 * pj + 2),
                                                at(2 * pi + 2, 2 * pj + 2), fx, fy);
        EXPECT_NEAR(vertices[k].parent, expected * 0.5, 1e-3) << "vertex " << i << ", " << j;
        EXPECT_FLOAT_EQ(vertices[k].own, static_cast<float>(at(i, j) * 0.5));
        if (i % 2 == 0 && j % 2 == 0) {
            EXPECT_EQ(vertices[k].own, vertices[k].parent) << "a parent sample does not move";
        }
    }
}

TEST(NodeVertexDataTest, APlaneHasItsOwnNormalEverywhere)
{
    // h = 3 i - 2 j + 2000 codes; with 0.25 m per code and 5 m spacing the slope is (0.15, -0.1).
    std::vector<std::uint16_t> codes = window([](int i, int j) { return 3.0 * i - 2.0 * j + 2000; });
    const TemplateMesh mesh = buildTemplateMesh(kN);
    const auto vertices = buildNodeVertices(mesh, metres(codes, 0.25), 5.0, {});
    const double length = std::sqrt(0.15 * 0.15 + 0.1 * 0.1 + 1);
    for (std::size_t k = 0; k < vertices.size(); ++k) {
        EXPECT_NEAR(vertices[k].ownNormal[0] / 32767.0, -0.15 / length, 1e-4);
        EXPECT_NEAR(vertices[k].ownNormal[1] / 32767.0, 0.1 / length, 1e-4);
        EXPECT_EQ(vertices[k].parentNormal[0], vertices[k].ownNormal[0]);
        EXPECT_EQ(vertices[k].parentNormal[1], vertices[k].ownNormal[1]);
        EXPECT_FLOAT_EQ(vertices[k].parent, vertices[k].own) << "a plane is its own parent surface";
    }
}

TEST(NodeVertexDataTest, SkirtVerticesCopyTheirEdgeVertex)
{
    std::vector<std::uint16_t> codes = window([](int i, int j) { return 1000 + 7 * i * j % 50; });
    const TemplateMesh mesh = buildTemplateMesh(kN);
    const auto vertices = buildNodeVertices(mesh, metres(codes, 1.0), 1.0, {});
    for (int r = 0; r < skirtRingLength(kN); ++r) {
        const GridCoord edge = skirtRingCoord(kN, r);
        const NodeVertex& skirt = vertices[skirtVertexIndex(kN, r)];
        const NodeVertex& top = vertices[gridVertexIndex(kN, edge.i, edge.j)];
        EXPECT_EQ(skirt.own, top.own);
        EXPECT_EQ(skirt.parent, top.parent);
        EXPECT_EQ(skirt.ownNormal[0], top.ownNormal[0]);
        EXPECT_EQ(skirt.parentNormal[1], top.parentNormal[1]);
    }
}

}  // namespace
}  // namespace terrain
