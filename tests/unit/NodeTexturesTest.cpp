// The node pools' texture data (lod/NodeTextures.h): DXT1 colour decoded here from the format's definition
// (two RGB565 end points, four colours on the line between them, 2-bit indices) and compared with the
// source texels, RGTC2 normal maps likewise (two signed 8-bit end points a channel, 3-bit indices), RGBA4 weights
// against the rounding rule, and the parent's normals against planes whose normal is known in closed form.
#include "MapTestSupport.h"

#include "lod/NodeTextures.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace terrain {
namespace {

/// The RGB of texel (x, y) of a DXT1 layer of `size` texels a side, decoded by the S3TC rules.
std::array<int, 3> decodeDxt1(const std::vector<std::uint8_t>& blocks, int size, int x, int y)
{
    const int perRow = size / 4;
    const std::uint8_t* b = blocks.data() + (static_cast<std::size_t>(y / 4) * perRow + x / 4) * 8;
    const int c0 = b[0] | b[1] << 8, c1 = b[2] | b[3] << 8;
    auto rgb = [](int c) {
        return std::array<double, 3>{((c >> 11) & 31) * 255.0 / 31.0, ((c >> 5) & 63) * 255.0 / 63.0,
                                     (c & 31) * 255.0 / 31.0};
    };
    const auto e0 = rgb(c0), e1 = rgb(c1);
    const std::uint32_t bits = b[4] | b[5] << 8 | b[6] << 16 | static_cast<std::uint32_t>(b[7]) << 24;
    const int index = static_cast<int>(bits >> (2 * ((y % 4) * 4 + x % 4)) & 3);
    std::array<int, 3> out{};
    for (int c = 0; c < 3; ++c) {
        double v = 0.0;
        if (c0 > c1) {
            const double w[4] = {0.0, 1.0, 1.0 / 3.0, 2.0 / 3.0};
            v = e0[c] + w[index] * (e1[c] - e0[c]);
        } else {
            const double w[4] = {0.0, 1.0, 0.5, 0.0};
            v = index == 3 ? 0.0 : e0[c] + w[index] * (e1[c] - e0[c]);
        }
        out[static_cast<std::size_t>(c)] = static_cast<int>(std::lround(v));
    }
    return out;
}

TEST(NodeTexturesTest, Dxt1KeepsATerrainTextureCloseAndPadsWithTheEdge)
{
    const int t = 65;
    ASSERT_EQ(blockLayerSize(t), 68);
    ASSERT_EQ(blockLayerSize(64), 64);
    // Smooth gradients with some noise, like a terrain's colours.
    std::vector<std::uint8_t> rgb(static_cast<std::size_t>(t) * t * 3);
    for (int j = 0; j < t; ++j) {
        for (int i = 0; i < t; ++i) {
            const double n = 12.0 * (test::unitNoise(7, i, j) - 0.5);
            std::uint8_t* p = rgb.data() + (static_cast<std::size_t>(j) * t + i) * 3;
            p[0] = static_cast<std::uint8_t>(std::clamp(90.0 + 1.5 * i + n, 0.0, 255.0));
            p[1] = static_cast<std::uint8_t>(std::clamp(110.0 + 1.2 * j + n, 0.0, 255.0));
            p[2] = static_cast<std::uint8_t>(std::clamp(60.0 + 0.5 * (i + j) + n, 0.0, 255.0));
        }
    }
    const std::vector<std::uint8_t> blocks = compressDxt1(rgb, t);
    ASSERT_EQ(blocks.size(), static_cast<std::size_t>(17 * 17 * 8));
    double sum = 0.0;
    int worst = 0;
    for (int j = 0; j < 68; ++j) {
        for (int i = 0; i < 68; ++i) {
            const auto got = decodeDxt1(blocks, 68, i, j);
            const std::uint8_t* want =
                rgb.data() + (static_cast<std::size_t>(std::min(j, t - 1)) * t + std::min(i, t - 1)) * 3;
            for (int c = 0; c < 3; ++c) {
                const int e = std::abs(got[static_cast<std::size_t>(c)] - want[c]);
                worst = std::max(worst, e);
                sum += e;
            }
        }
    }
    const double mean = sum / (68.0 * 68.0 * 3.0);
    std::printf("DXT1: mean error %.2f, worst %d of 255\n", mean, worst);
    EXPECT_LT(mean, 4.0);
    EXPECT_LE(worst, 24);
    // A constant texture comes back exactly (its colour is an end point) where the colour is 565-exact.
    std::vector<std::uint8_t> flat(static_cast<std::size_t>(t) * t * 3);
    for (std::size_t k = 0; k < flat.size(); k += 3) {
        flat[k] = 255;
        flat[k + 1] = 0;
        flat[k + 2] = 255;
    }
    const std::vector<std::uint8_t> flatBlocks = compressDxt1(flat, t);
    EXPECT_EQ(decodeDxt1(flatBlocks, 68, 67, 67), (std::array<int, 3>{255, 0, 255}));
    EXPECT_EQ(decodeDxt1(flatBlocks, 68, 3, 40), (std::array<int, 3>{255, 0, 255}));
}

/// Channel c (0: x, 1: y) of texel (x, y) of a signed RGTC2 layer of `size` texels a side, decoded by the
/// format's rules (two signed 8-bit end points; if the first is greater, six steps between them, else four
/// and the values -127 and 127; 3-bit indices), in 8-bit signed steps (not rounded).
double decodeRgtc2(const std::vector<std::uint8_t>& blocks, int size, int x, int y, int c)
{
    const int perRow = size / 4;
    const std::uint8_t* b = blocks.data() + (static_cast<std::size_t>(y / 4) * perRow + x / 4) * 16 + 8 * c;
    const double r0 = std::max(-127, static_cast<int>(static_cast<std::int8_t>(b[0])));
    const double r1 = std::max(-127, static_cast<int>(static_cast<std::int8_t>(b[1])));
    std::uint64_t bits = 0;
    for (int k = 0; k < 6; ++k) {
        bits |= static_cast<std::uint64_t>(b[2 + k]) << (8 * k);
    }
    const int index = static_cast<int>(bits >> (3 * ((y % 4) * 4 + x % 4)) & 7);
    if (index == 0) {
        return r0;
    }
    if (index == 1) {
        return r1;
    }
    if (static_cast<std::int8_t>(b[0]) > static_cast<std::int8_t>(b[1])) {
        return ((8 - index) * r0 + (index - 1) * r1) / 7.0;
    }
    if (index == 6) {
        return -127.0;
    }
    if (index == 7) {
        return 127.0;
    }
    return ((6 - index) * r0 + (index - 1) * r1) / 5.0;
}

TEST(NodeTexturesTest, Rgtc2KeepsANormalMapWithinItsBlocksStepsAndPadsWithTheEdge)
{
    const int t = 129;
    ASSERT_EQ(blockLayerSize(t), 132);
    // Unit normals of a rough surface (x, y as GL_RG8_SNORM): gentle slopes, steep ones up to the extremes,
    // and a flat corner, where every block is a single value.
    std::vector<std::int8_t> rg(static_cast<std::size_t>(t) * t * 2);
    for (int j = 0; j < t; ++j) {
        for (int i = 0; i < t; ++i) {
            const bool flat = i < 20 && j < 20;
            const double gx = flat ? 0.0 : 1.6 * std::sin(0.05 * i) + 0.4 * (test::unitNoise(3, i, j) - 0.5);
            const double gy = flat ? 0.0 : 2.5 * std::cos(0.07 * j + 0.02 * i) + 0.4 * (test::unitNoise(4, i, j) - 0.5);
            const double length = std::sqrt(gx * gx + gy * gy + 1.0);
            std::int8_t* p = rg.data() + (static_cast<std::size_t>(j) * t + i) * 2;
            p[0] = static_cast<std::int8_t>(std::lround(127.0 * -gx / length));
            p[1] = static_cast<std::int8_t>(std::lround(127.0 * -gy / length));
        }
    }
    rg[(static_cast<std::size_t>(100) * t + 100) * 2] = -127;  // the ends of the range
    rg[(static_cast<std::size_t>(100) * t + 101) * 2] = 127;
    const std::vector<std::uint8_t> blocks = compressRgtc2(rg, t);
    ASSERT_EQ(blocks.size(), static_cast<std::size_t>(33 * 33 * 16));
    auto source = [&](int i, int j, int c) {
        return static_cast<double>(rg[(static_cast<std::size_t>(std::min(j, t - 1)) * t + std::min(i, t - 1)) * 2 +
                                      static_cast<std::size_t>(c)]);
    };
    double worstAngle = 0.0, sumAngle = 0.0;
    for (int by = 0; by < 33; ++by) {
        for (int bx = 0; bx < 33; ++bx) {
            for (int c = 0; c < 2; ++c) {
                double lo = 127.0, hi = -127.0;
                for (int y = 4 * by; y < 4 * by + 4; ++y) {
                    for (int x = 4 * bx; x < 4 * bx + 4; ++x) {
                        lo = std::min(lo, source(x, y, c));
                        hi = std::max(hi, source(x, y, c));
                    }
                }
                for (int y = 4 * by; y < 4 * by + 4; ++y) {
                    for (int x = 4 * bx; x < 4 * bx + 4; ++x) {
                        const double got = decodeRgtc2(blocks, 132, x, y, c);
                        // Within half a step of the block's eight (a texel of a flat block exact), and never
                        // outside the block's own range.
                        ASSERT_LE(std::abs(got - source(x, y, c)), (hi - lo) / 14.0 + 0.5)
                            << "texel " << x << ", " << y << " channel " << c;
                        ASSERT_GE(got, lo - 1e-9);
                        ASSERT_LE(got, hi + 1e-9);
                    }
                }
            }
        }
    }
    for (int j = 0; j < t; ++j) {
        for (int i = 0; i < t; ++i) {
            auto normal = [](double x, double y) {
                x /= 127.0;
                y /= 127.0;
                return std::array<double, 3>{x, y, std::sqrt(std::max(0.0, 1.0 - x * x - y * y))};
            };
            const auto a = normal(source(i, j, 0), source(i, j, 1));
            const auto b = normal(decodeRgtc2(blocks, 132, i, j, 0), decodeRgtc2(blocks, 132, i, j, 1));
            const double dot = std::clamp(a[0] * b[0] + a[1] * b[1] + a[2] * b[2], -1.0, 1.0);
            const double angle = std::acos(dot) * 180.0 / 3.14159265358979;
            worstAngle = std::max(worstAngle, angle);
            sumAngle += angle;
        }
    }
    const double meanAngle = sumAngle / (t * t);
    std::printf("RGTC2: mean angle %.3f deg, worst %.3f deg\n", meanAngle, worstAngle);
    EXPECT_LT(meanAngle, 1.0);  // measured 0.81 on this rough field (the GL test compares shaded frames)
    // The flat corner is exact.
    EXPECT_EQ(decodeRgtc2(blocks, 132, 5, 5, 0), 0.0);
    EXPECT_EQ(decodeRgtc2(blocks, 132, 5, 5, 1), 0.0);
}

TEST(NodeTexturesTest, WeightsRoundToTheNearestSixteenth)
{
    const std::vector<std::uint8_t> weights = {0, 255, 17, 8, 9, 128, 136, 246};
    const std::vector<std::uint16_t> packed = packWeightsRgba4(weights);
    ASSERT_EQ(packed.size(), 2u);
    // 255 -> 15, 17 -> 1 (17 * 15 / 255 = 1.0), 8 -> 0 (0.47), 9 -> 1 (0.53), 128 -> 8 (7.53), 136 -> 8, 246 -> 14.
    EXPECT_EQ(packed[0], static_cast<std::uint16_t>(0x0 << 12 | 0xF << 8 | 0x1 << 4 | 0x0));
    EXPECT_EQ(packed[1], static_cast<std::uint16_t>(0x1 << 12 | 0x8 << 8 | 0x8 << 4 | 0xE));
}

TEST(NodeTexturesTest, ParentNormalsOfAPlaneAreItsNormal)
{
    const int n = 17, w = n + 4;
    const double spacing = 8.0;
    for (const auto& [a, b] : {std::pair{0.0, 0.0}, std::pair{3.0, -1.5}, std::pair{-20.0, 40.0}}) {
        std::vector<float> window(static_cast<std::size_t>(w) * w);
        for (int j = -2; j < n + 2; ++j) {
            for (int i = -2; i < n + 2; ++i) {
                window[static_cast<std::size_t>(j + 2) * w + i + 2] = static_cast<float>(500.0 + a * i + b * j);
            }
        }
        const std::vector<std::int8_t> normals = parentNormalsRg8(window, n, spacing);
        ASSERT_EQ(normals.size(), static_cast<std::size_t>(9 * 9 * 2));
        // z = 500 + (a x + b y) / spacing: normal (-a / s, -b / s, 1) / length.
        const double x = -a / spacing, y = -b / spacing, length = std::sqrt(x * x + y * y + 1.0);
        for (std::size_t k = 0; k < normals.size(); k += 2) {
            EXPECT_NEAR(normals[k] / 127.0, x / length, 0.5 / 127.0 + 1e-9);
            EXPECT_NEAR(normals[k + 1] / 127.0, y / length, 0.5 / 127.0 + 1e-9);
        }
    }
    // A bump at an odd sample is not seen (the parent has no sample there); at an even one it tilts the
    // parent's normals two samples away.
    std::vector<float> window(static_cast<std::size_t>(w) * w, 100.0f);
    window[static_cast<std::size_t>(5 + 2) * w + 7 + 2] = 140.0f;  // (7, 5): odd
    for (std::int8_t v : parentNormalsRg8(window, n, spacing)) {
        EXPECT_EQ(v, 0);
    }
    window[static_cast<std::size_t>(4 + 2) * w + 6 + 2] = 140.0f;  // (6, 4): the parent's (3, 2)
    const std::vector<std::int8_t> bumped = parentNormalsRg8(window, n, spacing);
    EXPECT_LT(bumped[(2 * 9 + 2) * 2], 0) << "west of the bump the ground rises to the east: the normal leans west";
    EXPECT_GT(bumped[(2 * 9 + 4) * 2], 0) << "east of it the normal leans east";
    EXPECT_EQ(bumped[(2 * 9 + 3) * 2], 0) << "at the bump the central difference is flat";
}

TEST(NodeTexturesTest, HeightsQuantizeWithinHalfAStepOfTheirRange)
{
    const int n = 17, w = n + 4;
    std::vector<float> window(static_cast<std::size_t>(w) * w);
    for (int j = 0; j < w; ++j) {
        for (int i = 0; i < w; ++i) {
            window[static_cast<std::size_t>(j) * w + i] = static_cast<float>(
                2400.0 + 300.0 * std::sin(0.3 * i) * std::cos(0.2 * j) + (i == 0 || j == 0 ? 5000.0 : 0.0));
        }
    }
    const QuantizedHeights q = quantizeHeightsR16(window, n);
    ASSERT_EQ(q.codes.size(), static_cast<std::size_t>((n + 2) * (n + 2)));
    // The range is the inner (N + 2)^2 only: the outer border (5000 m higher here) is not drawn.
    EXPECT_LT(q.range, 700.0f);
    EXPECT_EQ(*std::min_element(q.codes.begin(), q.codes.end()), 0);
    EXPECT_EQ(*std::max_element(q.codes.begin(), q.codes.end()), 65535);
    for (int j = 0; j < n + 2; ++j) {
        for (int i = 0; i < n + 2; ++i) {
            const double h = window[static_cast<std::size_t>(j + 1) * w + i + 1];
            const double decoded = q.lo + q.range * (q.codes[static_cast<std::size_t>(j) * (n + 2) + i] / 65535.0);
            EXPECT_LE(std::abs(decoded - h), q.range / 131070.0 + 1e-4) << i << "," << j;
        }
    }
    // A flat window: range 0, every code 0, decoded exactly.
    const QuantizedHeights flat = quantizeHeightsR16(std::vector<float>(static_cast<std::size_t>(w) * w, 12.5f), n);
    EXPECT_EQ(flat.range, 0.0f);
    EXPECT_EQ(flat.lo, 12.5f);
}

}  // namespace
}  // namespace terrain
