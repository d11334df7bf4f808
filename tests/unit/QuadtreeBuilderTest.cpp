// The quadtree builder (buildMap) and the static height query, checked through the maps they write:
// simplification errors against a brute-force evaluation of each node's triangulated surface, nested errors
// (eq. 3.1) and bounding boxes (3.2.12), exact or bounded round trips at every input sample, padding of
// odd-sized inputs, no-data filling, weight-map pruning (3.2.13), shared texture edges (3.2.7),
// determinism across thread counts, and clear errors for bad options.
#include "quadtree/QuadtreeBuilder.h"

#include "MapTestSupport.h"
#include "heightfield/Image.h"
#include "lod/HeightQuery.h"
#include "quadtree/MapVerifier.h"

#include <gtest/gtest.h>
#include <limits>
#include <mutex>
#include <set>

namespace terrain {
namespace {

/// A map built into a scratch directory, opened and fully decoded.
struct Built {
    std::filesystem::path path;
    BuildReport report;
    std::unique_ptr<MapFile> map;
    test::DecodedTree tree;

    const MapHeader& header() const { return map->header(); }
    const StaticNode& node(const NodeId& id) const { return *tree.find(id); }
};

/// Builds `field` (a copy: buildMap consumes it); on failure records it and returns a Built without map.
Built buildAndDecode(const test::ScratchDir& dir, HeightField field, const BuildOptions& options,
                     const std::string& name = "test.map")
{
    Built built;
    built.path = dir / name;
    auto report = buildMap(std::move(field), options, built.path);
    if (!report.ok()) {
        ADD_FAILURE() << "buildMap: " << report.error().message;
        return built;
    }
    built.report = report.value();
    built.map = test::openMap(built.path);
    if (!built.map) {
        return built;
    }
    auto tree = test::decodeTree(*built.map);
    if (!tree.ok()) {
        ADD_FAILURE() << tree.error().message;
        built.map.reset();
        return built;
    }
    built.tree = std::move(tree.value());
    return built;
}

/// Metres the map should store for a native value: -v scale (1 if absent) and --offset.
double metresOf(const BuildOptions& options, double native)
{
    return options.verticalScale.value_or(1.0) * native + options.offset;
}

/// A reproducible description of one build, for table-driven tests.
struct MapCase {
    const char* name;
    std::function<HeightField()> field;
    int chunk = 17;
    double maxError = 0.0;
    double scale = 1.0;
    double offset = 0.0;
    std::uint32_t heightCoding = kHeightCodingKobbeltResidual;

    BuildOptions options() const
    {
        BuildOptions o = test::testOptions(chunk);
        o.maxError = maxError;
        o.verticalScale = scale;
        o.offset = offset;
        o.heightCoding = heightCoding;
        return o;
    }
};

std::string caseName(const ::testing::TestParamInfo<MapCase>& paramInfo)
{
    return paramInfo.param.name;
}
void PrintTo(const MapCase& c, std::ostream* os)
{
    *os << c.name;
}

const MapCase kMapCases[] = {
    {"HillyLossless", [] { return test::hillyField(129, 129, 1); }, 17},
    {"RoughLosslessChunk9", [] { return test::roughField(65, 65, 2, 0, 3000); }, 9},
    {"RoughLossyE3", [] { return test::roughField(65, 65, 3, 100, 2100); }, 17, 3.0},
    {"HillyScaledOffsetPadded", [] { return test::hillyField(70, 41, 4); }, 17, 0.0, 0.5, -20.0},
    {"FractionalSamples", [] { return test::fractionalField(65, 65); }, 17},
    {"FractionalLossyE2", [] { return test::fractionalField(65, 65, 5); }, 9, 2.0},
    // Seed 003's fractal coding (quadtree/PifsCodec.h): lossy, its stored heights no longer the input's.
    {"HillyPifs", [] { return test::hillyField(129, 129, 1); }, 17, 0.0, 1.0, 0.0, kHeightCodingPifs},
    {"RoughPifsChunk9", [] { return test::roughField(65, 65, 2, 0, 3000); }, 9, 0.0, 1.0, 0.0, kHeightCodingPifs},
    {"HillyPifsScaledOffsetPadded", [] { return test::hillyField(70, 41, 4); }, 17, 0.0, 0.5, -20.0, kHeightCodingPifs},
};

// ---- Errors and bounds ----

class BuilderErrorsTest : public ::testing::TestWithParam<MapCase> {};

TEST_P(BuilderErrorsTest, DeltaMEqualsBruteForceEvaluationOfTheNodesTriangles)
{
    const MapCase& c = GetParam();
    test::ScratchDir dir;
    const HeightField field = c.field();
    const Built built = buildAndDecode(dir, field, c.options());
    ASSERT_TRUE(built.map);
    const MapHeader& h = built.header();
    const int n = static_cast<int>(h.chunkSize);
    const bool lossless = h.maxErrorBound == 0;
    int internal = 0;
    double largest = 0;
    for (const DirectoryEntry& entry : built.map->directory()) {
        if (!entry.hasChildren) {
            continue;
        }
        ++internal;
        const StaticNode& node = built.node(entry.id);
        const auto triangles =
            test::templateTriangles(n - 1, [&](int i, int j) { return h.heightOf(test::windowCode(h, node, i, j)); });
        // Every sample of the children's resolution in the node's square, from the input when the map is
        // lossless (independent of the decoder), else from the decoded children.
        const std::uint64_t stride = test::strideAt(h, entry.id.level + 1);
        double worst = 0;
        for (int b = 0; b <= 2 * (n - 1); ++b) {
            for (int a = 0; a <= 2 * (n - 1); ++a) {
                double sample = 0;
                if (lossless && field.integerSamples) {
                    const std::uint64_t gx = (std::uint64_t{entry.id.x} * 2 * (n - 1) + a) * stride;
                    const std::uint64_t gy = (std::uint64_t{entry.id.y} * 2 * (n - 1) + b) * stride;
                    sample = metresOf(c.options(), test::paddedNative(field, static_cast<std::int64_t>(gx),
                                                                      static_cast<std::int64_t>(gy)));
                } else {
                    const int qx = a >= n ? 1 : 0, qy = b >= n ? 1 : 0;  // either child holds a shared edge
                    const StaticNode& child = built.node(entry.id.child(qx | (qy << 1)));
                    sample = h.heightOf(test::windowCode(h, child, a - qx * (n - 1), b - qy * (n - 1)));
                }
                auto surface = test::heightInTriangles(triangles, a / 2.0, b / 2.0);
                ASSERT_TRUE(surface) << entry.id.toString() << " (" << a << ", " << b << ") lies in no triangle";
                worst = std::max(worst, std::abs(sample - *surface));
            }
        }
        largest = std::max(largest, worst);
        EXPECT_NEAR(entry.deltaM, worst, 1e-6 * std::max(1.0, worst)) << "node " << entry.id.toString();
    }
    EXPECT_GT(internal, 0);
    EXPECT_GT(largest, 0.0) << "the fixture should not be planar";
}

TEST_P(BuilderErrorsTest, DeltaCIsTheMeasuredDistanceToTheLeavesNestedWithMax)
{
    // Issue 12 (map version 4): delta_c = max(kErrorNesting x children's delta_c, the largest vertical
    // distance from the node's triangles to any sample of a stored leaf below it). Brute force: the decoded node's
    // triangles, searched generically, against every decoded leaf sample.
    const MapCase& c = GetParam();
    test::ScratchDir dir;
    const Built built = buildAndDecode(dir, c.field(), c.options());
    ASSERT_TRUE(built.map);
    const MapHeader& h = built.header();
    const int n = static_cast<int>(h.chunkSize);
    int measured = 0;
    double largestGain = 0.0;  // how much below eq. 3.1's sum the measured error comes
    for (const DirectoryEntry& entry : built.map->directory()) {
        if (!entry.hasChildren) {
            EXPECT_EQ(entry.deltaM, 0.0f) << "leaf " << entry.id.toString();
            EXPECT_EQ(entry.deltaC, 0.0f) << "leaf " << entry.id.toString();
            continue;
        }
        const StaticNode& node = built.node(entry.id);
        const auto triangles =
            test::templateTriangles(n - 1, [&](int i, int j) { return h.heightOf(test::windowCode(h, node, i, j)); });
        double direct = 0.0;
        for (const DirectoryEntry& leaf : built.map->directory()) {
            const int k = leaf.id.level - entry.id.level;
            if (leaf.hasChildren || k <= 0 || (leaf.id.x >> k) != entry.id.x || (leaf.id.y >> k) != entry.id.y) {
                continue;
            }
            const StaticNode& below = built.node(leaf.id);
            const double scale = std::ldexp(1.0, -k);
            const double x0 = (leaf.id.x - (entry.id.x << k)) * (n - 1.0) * scale;
            const double y0 = (leaf.id.y - (entry.id.y << k)) * (n - 1.0) * scale;
            for (int j = 0; j < n; ++j) {
                for (int i = 0; i < n; ++i) {
                    auto surface = test::heightInTriangles(triangles, x0 + i * scale, y0 + j * scale);
                    ASSERT_TRUE(surface) << entry.id.toString();
                    direct = std::max(direct, std::abs(h.heightOf(test::windowCode(h, below, i, j)) - *surface));
                }
            }
        }
        double worstChild = 0;
        for (int q = 0; q < 4; ++q) {
            const DirectoryEntry* child = built.map->find(entry.id.child(q));
            ASSERT_NE(child, nullptr) << entry.id.child(q).toString();
            worstChild = std::max<double>(worstChild, child->deltaC);
        }
        const double expected = std::max(kErrorNesting * worstChild, direct);
        if (c.heightCoding == kHeightCodingPifs) {
            // Fractal coding stores a bound (the input's distance plus the coding errors): at least this.
            EXPECT_GE(entry.deltaC, expected * (1 - 1e-5)) << "node " << entry.id.toString();
            ++measured;
            continue;
        }
        EXPECT_NEAR(entry.deltaC, expected, 1e-5 * std::max(1.0, expected)) << "node " << entry.id.toString();
        largestGain = std::max(largestGain, worstChild + entry.deltaM - entry.deltaC);
        ++measured;
    }
    EXPECT_GT(measured, 0);
    if (c.field().width >= 65 && c.heightCoding != kHeightCodingPifs) {
        EXPECT_GT(largestGain, 0.0) << "the measured error should be tighter than eq. 3.1 somewhere";
    }
    EXPECT_TRUE(verifyMap(*built.map).empty());
}

struct CodeRange {
    std::uint16_t lo = 65535;
    std::uint16_t hi = 0;
    void add(std::uint16_t code)
    {
        lo = std::min(lo, code);
        hi = std::max(hi, code);
    }
    void add(const CodeRange& r)
    {
        lo = std::min(lo, r.lo);
        hi = std::max(hi, r.hi);
    }
};

TEST_P(BuilderErrorsTest, BoundingBoxesContainEveryDescendantAndAreTight)
{
    const MapCase& c = GetParam();
    test::ScratchDir dir;
    const Built built = buildAndDecode(dir, c.field(), c.options());
    ASSERT_TRUE(built.map);
    const MapHeader& h = built.header();
    const int n = static_cast<int>(h.chunkSize);
    // Per subtree: the range of the nodes' own squares (must lie inside the box) and of every window sample
    // inside the grid, borders included (the box may not be looser than that).
    std::map<std::uint64_t, std::pair<CodeRange, CodeRange>> ranges;
    auto directory = built.map->directory();
    for (auto it = directory.rbegin(); it != directory.rend(); ++it) {  // children before parents
        const NodeId id = it->id;
        const StaticNode& node = built.node(id);
        const auto last = static_cast<std::int64_t>(h.levelGridSize(id.level)) - 1;
        CodeRange square, window;
        for (int v = -kBorder; v < n + kBorder; ++v) {
            for (int u = -kBorder; u < n + kBorder; ++u) {
                const std::int64_t gx = std::int64_t{id.x} * (n - 1) + u, gy = std::int64_t{id.y} * (n - 1) + v;
                if (gx < 0 || gy < 0 || gx > last || gy > last) {
                    continue;
                }
                const std::uint16_t code = test::windowCode(h, node, u, v);
                window.add(code);
                if (u >= 0 && v >= 0 && u < n && v < n) {
                    square.add(code);
                }
            }
        }
        if (it->hasChildren) {
            for (int q = 0; q < 4; ++q) {
                auto child = ranges.find(id.child(q).key());
                ASSERT_NE(child, ranges.end());
                square.add(child->second.first);
                window.add(child->second.second);
            }
        }
        ranges[id.key()] = {square, window};
        EXPECT_LE(it->minCode, square.lo) << id.toString() << ": a descendant's sample lies below the box";
        EXPECT_GE(it->maxCode, square.hi) << id.toString() << ": a descendant's sample lies above the box";
        EXPECT_GE(it->minCode, window.lo) << id.toString() << ": box looser than any decoded sample";
        EXPECT_LE(it->maxCode, window.hi) << id.toString() << ": box looser than any decoded sample";
    }
}

TEST_P(BuilderErrorsTest, ParentSamplesAreTheChildrensEvenSamplesAndOverlapsAgree)
{
    // 3.2.3: a parent's samples are exactly its children's even samples; and wherever two windows of one
    // level cover the same grid sample (shared edges, borders) they hold the same code: no cracks.
    const MapCase& c = GetParam();
    test::ScratchDir dir;
    const Built built = buildAndDecode(dir, c.field(), c.options());
    ASSERT_TRUE(built.map);
    const MapHeader& h = built.header();
    const int n = static_cast<int>(h.chunkSize);
    const int half = (n - 1) / 2;
    std::vector<std::map<std::pair<std::int64_t, std::int64_t>, std::uint16_t>> seen(h.levels);
    for (const DirectoryEntry& entry : built.map->directory()) {
        const StaticNode& node = built.node(entry.id);
        const auto last = static_cast<std::int64_t>(h.levelGridSize(entry.id.level)) - 1;
        for (int v = -kBorder; v < n + kBorder; ++v) {
            for (int u = -kBorder; u < n + kBorder; ++u) {
                const std::int64_t gx = std::int64_t{entry.id.x} * (n - 1) + u,
                                   gy = std::int64_t{entry.id.y} * (n - 1) + v;
                if (gx < 0 || gy < 0 || gx > last || gy > last) {
                    continue;
                }
                auto [it, inserted] = seen[static_cast<std::size_t>(entry.id.level)].try_emplace(
                    {gx, gy}, test::windowCode(h, node, u, v));
                ASSERT_TRUE(inserted || it->second == test::windowCode(h, node, u, v))
                    << entry.id.toString() << " disagrees with a neighbour at level grid (" << gx << ", " << gy << ")";
            }
        }
        if (entry.id.isRoot()) {
            continue;
        }
        const StaticNode& parent = built.node(entry.id.parent());
        const int qx = entry.id.quadrant() & 1, qy = entry.id.quadrant() >> 1;
        for (int v = 0; v < n; v += 2) {
            for (int u = 0; u < n; u += 2) {
                ASSERT_EQ(test::windowCode(h, node, u, v),
                          test::windowCode(h, parent, qx * half + u / 2, qy * half + v / 2))
                    << entry.id.toString() << " sample (" << u << ", " << v << ")";
            }
        }
    }
}

INSTANTIATE_TEST_SUITE_P(, BuilderErrorsTest, ::testing::ValuesIn(kMapCases), caseName);

// ---- Round trips through the height query ----

struct RoundTripCase {
    const char* name;
    std::function<HeightField()> field;
    int chunk = 17;
    double maxError = 0.0;
    double scale = 1.0;
    double offset = 0.0;
    std::uint32_t heightCoding = kHeightCodingKobbeltResidual;
};

void PrintTo(const RoundTripCase& c, std::ostream* os)
{
    *os << c.name;
}

class BuilderRoundTripTest : public ::testing::TestWithParam<RoundTripCase> {};

TEST_P(BuilderRoundTripTest, StaticHeightAtEveryInputSample)
{
    const RoundTripCase& c = GetParam();
    test::ScratchDir dir;
    HeightField field = c.field();
    field.originX = 1024.0;  // powers of two keep world positions exact
    field.originY = -512.0;
    BuildOptions options = test::testOptions(c.chunk);
    options.maxError = c.maxError;
    options.verticalScale = c.scale;
    options.offset = c.offset;
    options.heightCoding = c.heightCoding;
    const Built built = buildAndDecode(dir, field, options);
    ASSERT_TRUE(built.map);
    const MapHeader& h = built.header();
    const bool pifs = c.heightCoding == kHeightCodingPifs;
    const bool lossless = field.integerSamples && c.maxError < c.scale && !pifs;
    if (lossless) {
        EXPECT_EQ(h.maxErrorBound, 0.0);
        EXPECT_EQ(h.quantizerBin, 1u);
    } else {
        EXPECT_GT(h.maxErrorBound, 0.0);
        if (c.maxError > 0) {
            EXPECT_LE(h.maxErrorBound, c.maxError);
        }
    }
    double worst = 0;
    int mismatches = 0;
    for (int j = 0; j < field.height; ++j) {
        for (int i = 0; i < field.width; ++i) {
            const double x = field.originX + i * 2.0, y = field.originY + j * 2.0;
            const double expected = c.scale * field.at(i, j) + c.offset;
            auto sample = staticHeightAt(*built.map, x, y);
            ASSERT_TRUE(sample.ok()) << "(" << i << ", " << j << "): " << sample.error().message;
            const double error = std::abs(sample->height - expected);
            worst = std::max(worst, error);
            const bool good = lossless ? sample->height == expected : error <= h.maxErrorBound * (1 + 1e-9) + 1e-9;
            if (!good && ++mismatches <= 5) {
                ADD_FAILURE() << "sample (" << i << ", " << j << ") of " << field.width << "x" << field.height
                              << ": height " << sample->height << " from node " << sample->node.toString()
                              << ", input gives " << expected << " (bound " << h.maxErrorBound << " m)";
            }
        }
    }
    EXPECT_EQ(mismatches, 0);
    if (!lossless && !pifs) {  // a fractal map's bound is over every node (PifsCodecTest), not the leaves only
        // The bound is used, not just respected: a lossy map is actually lossy.
        EXPECT_GE(worst, 0.5 * h.maxErrorBound)
            << "largest error " << worst << " m of a " << h.maxErrorBound << " m bound";
    }
}

TEST_P(BuilderRoundTripTest, FractionalPositionsFollowTheTemplateTriangles)
{
    const RoundTripCase& c = GetParam();
    test::ScratchDir dir;
    const HeightField field = c.field();
    BuildOptions options = test::testOptions(c.chunk);
    options.maxError = c.maxError;
    options.verticalScale = c.scale;
    options.offset = c.offset;
    options.heightCoding = c.heightCoding;
    const Built built = buildAndDecode(dir, field, options);
    ASSERT_TRUE(built.map);
    const MapHeader& h = built.header();
    // The finest static level is the input grid: interpolate the decoded leaf samples (equal to the input
    // when lossless) over the 3 x 3 quads around the point with generic barycentric weights.
    auto storedAt = [&](std::int64_t gx, std::int64_t gy) {
        const int n1 = static_cast<int>(h.chunkSize) - 1;
        const std::int64_t lastLeaf = (std::int64_t{1} << (h.levels - 1)) - 1;
        const NodeId leaf{static_cast<int>(h.levels) - 1, static_cast<std::uint32_t>(std::min(gx / n1, lastLeaf)),
                          static_cast<std::uint32_t>(std::min(gy / n1, lastLeaf))};
        const StaticNode* node = built.tree.find(leaf);
        return node ? h.heightOf(test::windowCode(h, *node, static_cast<int>(gx - std::int64_t{leaf.x} * n1),
                                                  static_cast<int>(gy - std::int64_t{leaf.y} * n1)))
                    : std::numeric_limits<double>::quiet_NaN();
    };
    const bool lossless = field.integerSamples && c.maxError < c.scale && c.heightCoding != kHeightCodingPifs;
    for (int k = 0; k < 300; ++k) {
        const double fx = test::unitNoise(77, k, 0) * (field.width - 1);
        const double fy = k % 10 == 0 ? fx * (field.height - 1) / (field.width - 1)  // on a diagonal now and then
                                      : test::unitNoise(77, k, 1) * (field.height - 1);
        const auto i0 = static_cast<std::int64_t>(std::floor(fx)), j0 = static_cast<std::int64_t>(std::floor(fy));
        std::function<double(int, int)> z = [&](int di, int dj) {
            const std::int64_t gx = std::clamp<std::int64_t>(i0 - 1 + di, 0, field.width - 1);
            const std::int64_t gy = std::clamp<std::int64_t>(j0 - 1 + dj, 0, field.height - 1);
            return lossless ? c.scale * field.at(static_cast<int>(gx), static_cast<int>(gy)) + c.offset
                            : storedAt(gx, gy);
        };
        const auto triangles = test::templateTriangles(3, z);
        auto expected =
            test::heightInTriangles(triangles, fx - static_cast<double>(i0 - 1), fy - static_cast<double>(j0 - 1));
        ASSERT_TRUE(expected);
        auto sample = staticHeightAt(*built.map, fx * 2.0, fy * 2.0);
        ASSERT_TRUE(sample.ok()) << sample.error().message;
        EXPECT_NEAR(sample->height, *expected, 1e-6) << "at sample position (" << fx << ", " << fy << ")";
        EXPECT_EQ(sample->node.level, static_cast<int>(h.levels) - 1) << "at (" << fx << ", " << fy << ")";
    }
}

INSTANTIATE_TEST_SUITE_P(
    , BuilderRoundTripTest,
    ::testing::Values(
        RoundTripCase{"HillyLossless", [] { return test::hillyField(65, 65, 6); }},
        RoundTripCase{"RoughScaledOffset", [] { return test::roughField(65, 65, 7, 0, 5000); }, 9, 0.0, 2.0, 100.0},
        RoundTripCase{"RoughPadded70x41", [] { return test::roughField(70, 41, 8, 0, 1000); }},
        RoundTripCase{"RoughPadded41x70", [] { return test::roughField(41, 70, 9, 0, 1000); }},
        // The last valid column / row lies on a node edge, so a node beside it is padding only.
        RoundTripCase{"RoughEdgeOnNodeBoundary33x40", [] { return test::roughField(33, 40, 10, 0, 1000); }},
        RoundTripCase{"RoughEdgeOnNodeBoundary40x33", [] { return test::roughField(40, 33, 11, 0, 1000); }},
        RoundTripCase{"Smallest2x2", [] { return test::roughField(2, 2, 12, 0, 1000); }, 3},
        RoundTripCase{"TwoRows5x2", [] { return test::roughField(5, 2, 13, 0, 1000); }, 3},
        RoundTripCase{"ConstantHeight", [] { return test::makeHeightField(33, 33, [](int, int) { return 77.0f; }); }},
        RoundTripCase{"MaxErrorBelowOneStepIsLossless", [] { return test::roughField(33, 33, 14, 0, 1000); }, 17, 0.9},
        RoundTripCase{"RoughLossyE2", [] { return test::roughField(65, 65, 15, 0, 3000); }, 17, 2.0},
        RoundTripCase{"RoughLossyE7Scaled", [] { return test::roughField(65, 65, 16, 0, 3000); }, 9, 7.0, 0.5, 3.0},
        RoundTripCase{"FractionalLossless", [] { return test::fractionalField(65, 65, 17); }},
        RoundTripCase{"FractionalLossyE1", [] { return test::fractionalField(65, 65, 18); }, 17, 1.0},
        RoundTripCase{"RoughPifs", [] { return test::roughField(65, 65, 19, 0, 3000); }, 17, 0.0, 1.0, 0.0,
                      kHeightCodingPifs},
        RoundTripCase{"RoughPifsPadded70x41Chunk9", [] { return test::roughField(70, 41, 20, 0, 1000); }, 9, 0.0, 2.0,
                      100.0, kHeightCodingPifs},
        RoundTripCase{"FractionalPifs", [] { return test::fractionalField(65, 65, 21); }, 17, 0.0, 1.0, 0.0,
                      kHeightCodingPifs}),
    [](const auto& paramInfo) { return std::string(paramInfo.param.name); });

// ---- Determinism ----

TEST(QuadtreeBuilderTest, FileIsByteIdenticalForAnyThreadCount)
{
    struct Case {
        const char* name;
        HeightField field;
        double maxError;
        bool detail = false;  ///< with leaf detail errors
        std::uint32_t heightCoding = kHeightCodingKobbeltResidual;
    };
    const Case cases[] = {{"lossless", test::hillyField(129, 129, 19), 0.0},
                          {"lossy padded", test::roughField(129, 100, 20, 0, 4000), 3.0},
                          {"lossy padded, leaf detail errors", test::roughField(129, 100, 20, 0, 4000), 3.0, true},
                          {"fractal padded", test::roughField(129, 100, 20, 0, 4000), 0.0, true, kHeightCodingPifs}};
    for (const Case& c : cases) {
        test::ScratchDir dir;
        test::Bytes reference;
        for (int threads : {1, 2, 3, 4, 8}) {
            BuildOptions options = test::testOptions(17, threads);
            options.maxError = c.maxError;
            options.heightCoding = c.heightCoding;
            if (c.detail) {
                options.leafDetailError = test::fakeLeafDetailError;
            }
            const auto path = dir / ("t" + std::to_string(threads) + ".map");
            auto report = buildMap(c.field, options, path);
            ASSERT_TRUE(report.ok()) << report.error().message;
            auto bytes = test::readFileBytes(path);
            if (threads == 1) {
                reference = std::move(bytes);
                ASSERT_GT(reference.size(), kHeaderBytes);
            } else {
                EXPECT_TRUE(bytes == reference) << c.name << ": " << threads << " threads wrote a different file";
            }
        }
    }
}

// ---- Padding ----

struct PaddingCase {
    int width, height, chunk;
    std::uint32_t levels;  ///< smallest L with (N - 1) 2^(L-1) + 1 >= max(width, height)
};

TEST(QuadtreeBuilderTest, OddSizedInputsArePaddedByReplicatingTheLastRowAndColumn)
{
    const PaddingCase cases[] = {
        {70, 41, 17, 4}, {41, 70, 17, 4}, {33, 40, 17, 3}, {65, 65, 17, 3}, {66, 2, 17, 4}, {5, 2, 3, 2}, {2, 2, 3, 1},
    };
    for (const PaddingCase& c : cases) {
        SCOPED_TRACE(std::to_string(c.width) + "x" + std::to_string(c.height) + " chunk " + std::to_string(c.chunk));
        test::ScratchDir dir;
        const HeightField field = test::roughField(c.width, c.height, 21, 10, 900);
        const Built built = buildAndDecode(dir, field, test::testOptions(c.chunk));
        ASSERT_TRUE(built.map);
        const MapHeader& h = built.header();
        EXPECT_EQ(h.levels, c.levels);
        EXPECT_EQ(h.validX0, 0u);
        EXPECT_EQ(h.validY0, 0u);
        EXPECT_EQ(h.validWidth, static_cast<std::uint32_t>(c.width));
        EXPECT_EQ(h.validHeight, static_cast<std::uint32_t>(c.height));
        const int n = c.chunk;
        const std::int64_t validX1 = c.width - 1, validY1 = c.height - 1;
        for (const DirectoryEntry& entry : built.map->directory()) {
            const NodeId id = entry.id;
            const std::uint64_t stride = test::strideAt(h, id.level);
            const auto size = static_cast<std::int64_t>(stride) * (n - 1);  // node side in finest samples
            const std::int64_t x0 = id.x * size, y0 = id.y * size;
            if (x0 > validX1 || y0 > validY1) {
                EXPECT_FALSE(entry.hasChildren) << id.toString() << " lies wholly in the padding";
            } else if (x0 < validX1 && y0 < validY1 && id.level + 1 < static_cast<int>(h.levels)) {
                EXPECT_TRUE(entry.hasChildren) << id.toString() << " covers input samples";
            }
            // Every window sample: the padded input at the node's level, reflected beyond the grid.
            const StaticNode& node = built.node(id);
            const auto last = static_cast<std::int64_t>(h.levelGridSize(id.level)) - 1;
            auto inside = [&](std::int64_t gx, std::int64_t gy) {
                const double native = test::paddedNative(field, gx * static_cast<std::int64_t>(stride),
                                                         gy * static_cast<std::int64_t>(stride));
                return static_cast<std::uint16_t>(std::lround((native - h.heightOffset) / h.heightStep));
            };
            for (int v = -kBorder; v < n + kBorder; ++v) {
                for (int u = -kBorder; u < n + kBorder; ++u) {
                    const auto expected = test::reflectedCode(inside, last, std::int64_t{id.x} * (n - 1) + u,
                                                              std::int64_t{id.y} * (n - 1) + v);
                    ASSERT_EQ(test::windowCode(h, node, u, v), expected)
                        << id.toString() << " window (" << u << ", " << v << ")";
                }
            }
        }
        EXPECT_TRUE(verifyMap(*built.map).empty());
    }
}

// ---- No data ----

TEST(QuadtreeBuilderTest, NoDataSamplesAreFilledCountedAndFlagged)
{
    const float nan = std::numeric_limits<float>::quiet_NaN();
    HeightField field = test::hillyField(65, 65, 22);
    const HeightField original = field;
    // A 3x3 hole, one on the west edge and the north-east corner. They sit on samples of every node whose
    // square holds them (the block's (20, 32), the corner, and (0, 10) for levels 1-2), so "a node with a
    // filled sample" and "a node whose square holds a filled sample" mean the same here.
    std::vector<std::pair<int, int>> holes = {{0, 10}, {64, 64}};
    for (int j = 30; j <= 32; ++j) {
        for (int i = 20; i <= 22; ++i) {
            holes.emplace_back(i, j);
        }
    }
    for (auto [i, j] : holes) {
        field.at(i, j) = nan;
    }
    test::ScratchDir dir;
    const Built built = buildAndDecode(dir, field, test::testOptions(17));
    ASSERT_TRUE(built.map);
    const MapHeader& h = built.header();
    EXPECT_EQ(h.noDataFilled, holes.size());
    EXPECT_TRUE(verifyMap(*built.map).empty());
    auto isHole = [&](int i, int j) { return std::find(holes.begin(), holes.end(), std::pair{i, j}) != holes.end(); };
    for (int j = 0; j < 65; ++j) {
        for (int i = 0; i < 65; ++i) {
            auto sample = staticHeightAt(*built.map, i * 2.0, j * 2.0);
            ASSERT_TRUE(sample.ok()) << sample.error().message;
            if (!isHole(i, j)) {
                EXPECT_EQ(sample->height, original.at(i, j)) << "valid sample (" << i << ", " << j << ")";
                continue;
            }
            // Filled from the valid rim: within the range of the valid samples around the hole.
            double lo = 1e300, hi = -1e300;
            for (int dj = -2; dj <= 2; ++dj) {
                for (int di = -2; di <= 2; ++di) {
                    const int x = i + di, y = j + dj;
                    if (x >= 0 && y >= 0 && x < 65 && y < 65 && !isHole(x, y)) {
                        lo = std::min<double>(lo, original.at(x, y));
                        hi = std::max<double>(hi, original.at(x, y));
                    }
                }
            }
            EXPECT_GE(sample->height, std::floor(lo)) << "hole (" << i << ", " << j << ")";
            EXPECT_LE(sample->height, std::ceil(hi)) << "hole (" << i << ", " << j << ")";
        }
    }
    for (const DirectoryEntry& entry : built.map->directory()) {
        const auto size = static_cast<int>(test::strideAt(h, entry.id.level) * 16);
        const int x0 = static_cast<int>(entry.id.x) * size, y0 = static_cast<int>(entry.id.y) * size;
        bool holds = false;
        for (auto [i, j] : holes) {
            holds = holds || (i >= x0 && i <= x0 + size && j >= y0 && j <= y0 + size);
        }
        EXPECT_EQ(entry.hasFilledNoData, holds) << "node " << entry.id.toString();
    }
}

// ---- Weight-map pruning ----

/// A gray weight image, `pixel(x, row)` with row 0 north.
test::Bytes grayPixels(int width, int height, const std::function<std::uint8_t(int, int)>& pixel)
{
    test::Bytes pixels(static_cast<std::size_t>(width) * height);
    for (int row = 0; row < height; ++row) {
        for (int x = 0; x < width; ++x) {
            pixels[static_cast<std::size_t>(row) * width + x] = pixel(x, row);
        }
    }
    return pixels;
}

/// Every node has four children or none, every child's parent is flagged, and the counts agree.
void expectFourChildrenOrNone(const MapFile& map)
{
    std::size_t flagged = 0;
    for (const DirectoryEntry& entry : map.directory()) {
        if (entry.hasChildren) {
            ++flagged;
            for (int q = 0; q < 4; ++q) {
                EXPECT_NE(map.find(entry.id.child(q)), nullptr) << entry.id.toString() << " child " << q;
            }
        }
        if (!entry.id.isRoot()) {
            const DirectoryEntry* parent = map.find(entry.id.parent());
            EXPECT_TRUE(parent && parent->hasChildren) << entry.id.toString();
        }
    }
    EXPECT_EQ(map.directory().size(), 1 + 4 * flagged);
}

TEST(QuadtreeBuilderTest, WeightMapBlackLeftWhiteRightRefinesOnlyTheRight)
{
    // 129 x 129 samples, chunk 17: 4 levels; a 129-pixel-wide image puts pixel centres on the samples.
    // Columns 0..63 black, 64..128 white: a node keeps children exactly when its closed square reaches x = 64.
    test::ScratchDir dir;
    const HeightField field = test::roughField(129, 129, 23, 0, 2000);
    Image weights{129, 129, 1,
                  grayPixels(129, 129, [](int x, int) { return static_cast<std::uint8_t>(x >= 64 ? 255 : 0); })};
    ASSERT_TRUE(writePngImage(dir / "weights.png", weights).ok());
    BuildOptions options = test::testOptions(17);
    options.weights = dir / "weights.png";
    const Built built = buildAndDecode(dir, field, options);
    ASSERT_TRUE(built.map);
    const MapHeader& h = built.header();
    ASSERT_EQ(h.levels, 4u);
    std::size_t expectedNodes = 1;
    for (const DirectoryEntry& entry : built.map->directory()) {
        const auto size = static_cast<std::uint32_t>(128u >> entry.id.level);
        const bool wanted = entry.id.level < 3 && (entry.id.x + 1) * size >= 64;
        EXPECT_EQ(entry.hasChildren, wanted) << entry.id.toString();
        expectedNodes += wanted ? 4 : 0;
    }
    EXPECT_EQ(built.map->directory().size(), expectedNodes);
    expectFourChildrenOrNone(*built.map);
    EXPECT_TRUE(verifyMap(*built.map).empty());
    // Full depth on the right: exact heights from leaves; the west quarter stays at level 2 or above.
    for (int j = 0; j < 129; j += 3) {
        for (int i = 0; i < 129; ++i) {
            auto sample = staticHeightAt(*built.map, i * 2.0, j * 2.0);
            ASSERT_TRUE(sample.ok()) << sample.error().message;
            if (i >= 64) {
                EXPECT_EQ(sample->node.level, 3) << "(" << i << ", " << j << ")";
                EXPECT_EQ(sample->height, field.at(i, j)) << "(" << i << ", " << j << ")";
            } else if (i < 32) {
                EXPECT_LE(sample->node.level, 2) << "(" << i << ", " << j << ")";
            }
        }
    }
}

TEST(QuadtreeBuilderTest, UniformWeightsChooseTheDepth)
{
    struct Case {
        std::uint8_t gray;
        std::size_t nodes;  // levels kept = round(gray / 255 * 3) + 1
    };
    const Case cases[] = {{0, 1}, {84, 5}, {128, 21}, {255, 85}};
    for (const Case& c : cases) {
        test::ScratchDir dir;
        Image weights{9, 5, 1, test::Bytes(45, c.gray)};  // any size: stretched over the input
        ASSERT_TRUE(writePngImage(dir / "w.png", weights).ok());
        BuildOptions options = test::testOptions(17);
        options.weights = dir / "w.png";
        const Built built = buildAndDecode(dir, test::hillyField(129, 129, 24), options);
        ASSERT_TRUE(built.map);
        EXPECT_EQ(built.map->directory().size(), c.nodes) << "gray " << int{c.gray};
        expectFourChildrenOrNone(*built.map);
        EXPECT_TRUE(verifyMap(*built.map).empty()) << "gray " << int{c.gray};
    }
}

// ---- Leaf detail errors (3.4.1) ----

TEST(QuadtreeBuilderTest, LeafDetailErrorsAreAskedOncePerLeafAndNestIntoDetailDeltaC)
{
    struct Case {
        const char* name;
        HeightField field;
        int chunk;
        std::uint8_t westWeight;  ///< gray of a weight map's west half (east half white); 255: no pruning
        bool estimator;           ///< false: no leafDetailError, detailDeltaC must equal deltaC
    };
    const Case cases[] = {
        {"full tree", test::hillyField(129, 129, 31), 17, 255, true},
        {"full tree, no estimator", test::hillyField(129, 129, 31), 17, 255, false},
        {"padded", test::roughField(70, 41, 32, 0, 3000), 9, 255, true},
        {"pruned west half: leaves on three levels", test::roughField(129, 129, 33, 0, 2000), 17, 100, true},
        {"root alone", test::hillyField(17, 17, 34), 17, 255, true},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        test::ScratchDir dir;
        BuildOptions options = test::testOptions(c.chunk, 2);
        if (c.westWeight != 255) {
            auto gray = [&](int x, int) { return x < 4 ? c.westWeight : std::uint8_t{255}; };
            Image weights{8, 8, 1, grayPixels(8, 8, gray)};
            ASSERT_TRUE(writePngImage(dir / "w.png", weights).ok());
            options.weights = dir / "w.png";
        }
        std::mutex mutex;
        std::map<std::uint64_t, std::vector<std::uint16_t>> asked;  // by key: the window each leaf was given
        int repeats = 0;
        if (c.estimator) {
            options.leafDetailError = [&](const MapHeader& h, const NodeId& id, std::span<const std::uint16_t> window) {
                EXPECT_EQ(window.size(), static_cast<std::size_t>(h.windowSize() * h.windowSize()));
                std::lock_guard lock(mutex);
                repeats += asked.count(id.key()) ? 1 : 0;
                asked[id.key()].assign(window.begin(), window.end());
                return test::fakeLeafDetailError(h, id, window);
            };
        }
        const Built built = buildAndDecode(dir, c.field, options);
        ASSERT_TRUE(built.map);
        EXPECT_TRUE(built.header().hasDetailErrors());
        EXPECT_EQ(repeats, 0);
        std::set<int> leafLevels;
        float largest = 0.0f;
        double sum = 0.0;
        for (const DirectoryEntry& entry : built.map->directory()) {
            const std::string node = entry.id.toString();
            EXPECT_GE(entry.detailDeltaC, entry.deltaC) << node;
            if (!entry.hasChildren) {
                leafLevels.insert(entry.id.level);
                const float expected = c.estimator ? test::fakeLeafDetailError(built.header(), entry.id, {}) : 0.0f;
                EXPECT_EQ(entry.detailDeltaC, expected) << node;
                largest = std::max(largest, entry.detailDeltaC);
                sum += entry.detailDeltaC;
                if (c.estimator) {
                    // The window it was given is the leaf's stored window.
                    auto it = asked.find(entry.id.key());
                    ASSERT_NE(it, asked.end()) << node << " was never asked for";
                    EXPECT_EQ(it->second, built.node(entry.id).heights) << node;
                }
                continue;
            }
            EXPECT_FALSE(asked.count(entry.id.key())) << "inner node " << node << " was asked for";
            float worstChild = 0.0f;
            for (int q = 0; q < 4; ++q) {
                worstChild = std::max(worstChild, built.map->find(entry.id.child(q))->detailDeltaC);
            }
            // Issue 12: at least the children's, and the node's measured error plus the largest leaf detail
            // error below (detailDisplacementRange is 0 here); without an estimator, delta_c.
            float leafDetail = 0.0f;
            for (const DirectoryEntry& leaf : built.map->directory()) {
                const int k = leaf.id.level - entry.id.level;
                if (!leaf.hasChildren && k > 0 && (leaf.id.x >> k) == entry.id.x && (leaf.id.y >> k) == entry.id.y) {
                    leafDetail = std::max(leafDetail, leaf.detailDeltaC);
                }
            }
            EXPECT_GE(entry.detailDeltaC, kErrorNesting * worstChild * (1 - 1e-6f)) << node;
            EXPECT_GE(entry.detailDeltaC, leafDetail) << node;
            if (c.estimator) {
                // Its own measured error (<= delta_c) plus that: at most delta_c + leafDetail.
                EXPECT_LE(entry.detailDeltaC, std::max(kErrorNesting * worstChild, entry.deltaC + leafDetail) + 1e-3f)
                    << node;
            } else {
                EXPECT_EQ(entry.detailDeltaC, entry.deltaC) << node;
            }
        }
        EXPECT_EQ(asked.size(), c.estimator ? built.report.leaves : 0u);
        EXPECT_EQ(built.report.leaves, built.map->directory().size() - (built.map->directory().size() - 1) / 4);
        EXPECT_EQ(built.report.maxLeafDetailError, largest);
        EXPECT_NEAR(built.report.meanLeafDetailError, sum / static_cast<double>(built.report.leaves), 1e-9);
        if (c.westWeight != 255) {
            EXPECT_GE(leafLevels.size(), 2u) << "the weight map should leave leaves on several levels";
        }
        EXPECT_TRUE(verifyMap(*built.map).empty());
    }
}

// ---- Textures ----

struct TextureCase {
    const char* name;
    int width, height, chunk, textureSize;
    bool image;        ///< -t with a random RGB image instead of generated colours
    bool halfWeights;  ///< prune the west half with a weight map
};

void PrintTo(const TextureCase& c, std::ostream* os)
{
    *os << c.name;
}

class BuilderTextureTest : public ::testing::TestWithParam<TextureCase> {};

TEST_P(BuilderTextureTest, NeighboursOfOneLevelShareTheirEdgeTexels)
{
    const TextureCase& c = GetParam();
    test::ScratchDir dir;
    BuildOptions options = test::testOptions(c.chunk);
    options.textureSize = c.textureSize;
    if (c.image) {
        Image rgb{37, 23, 3, test::Bytes(37 * 23 * 3)};
        for (std::size_t i = 0; i < rgb.pixels.size(); ++i) {
            rgb.pixels[i] = static_cast<std::uint8_t>(test::hashNoise(25, static_cast<std::int64_t>(i), 0));
        }
        ASSERT_TRUE(writePngImage(dir / "texture.png", rgb).ok());
        options.texture = dir / "texture.png";
    }
    if (c.halfWeights) {
        Image weights{c.width, c.height, 1, grayPixels(c.width, c.height, [&](int x, int) {
                          return static_cast<std::uint8_t>(x >= c.width / 2 ? 255 : 0);
                      })};
        ASSERT_TRUE(writePngImage(dir / "weights.png", weights).ok());
        options.weights = dir / "weights.png";
    }
    const Built built = buildAndDecode(dir, test::hillyField(c.width, c.height, 26), options);
    ASSERT_TRUE(built.map);
    const MapHeader& h = built.header();
    const int t = static_cast<int>(h.textureSize);
    ASSERT_EQ(t, c.textureSize == 0 ? c.chunk : c.textureSize);
    auto texel = [&](const StaticNode& node, int tx, int ty, int channel) {
        return node.texture[(static_cast<std::size_t>(ty) * t + tx) * 3 + channel];
    };
    int pairs = 0, mismatches = 0;
    for (const DirectoryEntry& entry : built.map->directory()) {
        const StaticNode& a = built.node(entry.id);
        for (int direction = 0; direction < 2; ++direction) {  // 0: east neighbour, 1: north neighbour
            const NodeId b{entry.id.level, entry.id.x + (direction == 0 ? 1u : 0u),
                           entry.id.y + (direction == 1 ? 1u : 0u)};
            const std::uint32_t side = 1u << b.level;
            const StaticNode* nb = b.x < side && b.y < side ? built.tree.find(b) : nullptr;
            if (!nb) {
                continue;
            }
            ++pairs;
            for (int k = 0; k < t; ++k) {
                for (int channel = 0; channel < 3; ++channel) {
                    const int ours = direction == 0 ? texel(a, t - 1, k, channel) : texel(a, k, t - 1, channel);
                    const int theirs = direction == 0 ? texel(*nb, 0, k, channel) : texel(*nb, k, 0, channel);
                    if (ours != theirs && ++mismatches <= 5) {
                        ADD_FAILURE() << entry.id.toString() << (entry.hasChildren ? " (inner)" : " (leaf)") << " and "
                                      << b.toString() << (built.map->find(b)->hasChildren ? " (inner)" : " (leaf)")
                                      << ": shared edge texel " << k << " channel " << channel << " is " << ours
                                      << " vs " << theirs;
                    }
                }
            }
        }
    }
    EXPECT_GT(pairs, 0);
    EXPECT_EQ(mismatches, 0);
}

INSTANTIATE_TEST_SUITE_P(, BuilderTextureTest,
                         ::testing::Values(TextureCase{"Generated", 65, 65, 17, 0, false, false},
                                           TextureCase{"Image", 65, 65, 17, 0, true, false},
                                           TextureCase{"GeneratedTexture9", 65, 65, 17, 9, false, false},
                                           TextureCase{"ImageTexture33", 65, 65, 17, 33, true, false},
                                           TextureCase{"GeneratedPadded70x41", 70, 41, 17, 0, false, false},
                                           TextureCase{"ImagePruned", 129, 129, 17, 0, true, true},
                                           TextureCase{"GeneratedPruned", 129, 129, 17, 0, false, true}),
                         [](const auto& paramInfo) { return std::string(paramInfo.param.name); });

// ---- Bad options ----

TEST(QuadtreeBuilderTest, BadOptionsAndInputsAreErrorsThatLeaveNoFile)
{
    const float nan = std::numeric_limits<float>::quiet_NaN();
    struct Case {
        const char* what;
        HeightField field;
        std::function<void(BuildOptions&)> change;
        const char* mentions;
    };
    const Case cases[] = {
        {"chunk 64", test::hillyField(65, 65), [](BuildOptions& o) { o.chunkSize = 64; }, "chunk size 64"},
        {"chunk 1", test::hillyField(65, 65), [](BuildOptions& o) { o.chunkSize = 1; }, "chunk size 1"},
        {"chunk 2049", test::hillyField(65, 65), [](BuildOptions& o) { o.chunkSize = 2049; }, "chunk size 2049"},
        {"texture size 100", test::hillyField(65, 65), [](BuildOptions& o) { o.textureSize = 100; },
         "texture size 100"},
        {"texture size 2", test::hillyField(65, 65), [](BuildOptions& o) { o.textureSize = 2; }, "texture size 2"},
        {"threads 0", test::hillyField(65, 65), [](BuildOptions& o) { o.threads = 0; }, "thread count 0"},
        {"negative max error", test::hillyField(65, 65), [](BuildOptions& o) { o.maxError = -1; }, "error -1"},
        {"NaN max error", test::hillyField(65, 65), [](BuildOptions& o) { o.maxError = std::nan(""); }, "error"},
        {"negative spacing", test::hillyField(65, 65), [](BuildOptions& o) { o.spacing = -2.0; }, "spacing -2"},
        {"zero vertical scale", test::hillyField(65, 65), [](BuildOptions& o) { o.verticalScale = 0.0; }, "scale 0"},
        {"infinite offset", test::hillyField(65, 65),
         [](BuildOptions& o) { o.offset = std::numeric_limits<double>::infinity(); }, "offset"},
        {"1x1 input", test::hillyField(1, 1), [](BuildOptions&) {}, "1x1"},
        {"1x40 input", test::hillyField(1, 40), [](BuildOptions&) {}, "1x40"},
        {"0x0 input", HeightField{}, [](BuildOptions&) {}, "0x0"},
        {"all NaN", test::makeHeightField(9, 9, [&](int, int) { return nan; }), [](BuildOptions&) {},
         "no valid sample"},
        {"missing weight map", test::hillyField(65, 65), [](BuildOptions& o) { o.weights = "/nonexistent/w.png"; },
         "/nonexistent/w.png"},
        {"missing texture", test::hillyField(65, 65), [](BuildOptions& o) { o.texture = "/nonexistent/t.png"; },
         "/nonexistent/t.png"},
    };
    for (const Case& c : cases) {
        test::ScratchDir dir;
        BuildOptions options = test::testOptions(17);
        c.change(options);
        auto report = buildMap(c.field, options, dir / "out.map");
        ASSERT_FALSE(report.ok()) << c.what << " was accepted";
        EXPECT_NE(report.error().message.find(c.mentions), std::string::npos)
            << c.what << ": '" << report.error().message << "' does not mention '" << c.mentions << "'";
        EXPECT_TRUE(dir.list().empty()) << c.what << " left a file behind";
    }
}

TEST(QuadtreeBuilderTest, SingleValidSampleFillsTheWholeField)
{
    const float nan = std::numeric_limits<float>::quiet_NaN();
    HeightField field = test::makeHeightField(9, 9, [&](int i, int j) { return i == 4 && j == 4 ? 321.0f : nan; });
    test::ScratchDir dir;
    const Built built = buildAndDecode(dir, field, test::testOptions(5));
    ASSERT_TRUE(built.map);
    EXPECT_EQ(built.header().noDataFilled, 80u);
    for (int j = 0; j < 9; ++j) {
        for (int i = 0; i < 9; ++i) {
            auto sample = staticHeightAt(*built.map, i * 2.0, j * 2.0);
            ASSERT_TRUE(sample.ok()) << sample.error().message;
            EXPECT_EQ(sample->height, 321.0);
        }
    }
}

// ---- Height queries outside the terrain ----

TEST(HeightQueryTest, PositionsOutsideTheValidRegionAreErrorsNamingTheMap)
{
    test::ScratchDir dir;
    HeightField field = test::hillyField(70, 41, 27);  // padded to 129 x 129: the padding is outside too
    field.originX = 100.0;
    field.originY = 200.0;
    const Built built = buildAndDecode(dir, field, test::testOptions(17));
    ASSERT_TRUE(built.map);
    const double inf = std::numeric_limits<double>::infinity();
    struct Case {
        double x, y;
        bool inside;
    };
    const Case cases[] = {
        {100.0, 200.0, true},                    // south-west corner sample
        {100.0 + 69 * 2, 200.0 + 40 * 2, true},  // north-east corner sample
        {99.999, 250.0, false},                  // just west
        {100.0 + 69 * 2 + 0.001, 250.0, false},  // just east of the last column
        {150.0, 199.99, false},                  // just south
        {150.0, 200.0 + 40 * 2 + 0.01, false},   // just north of the last row, inside the padded grid
        {100.0 + 100 * 2, 200.0, false},         // in the padding
        {std::nan(""), 250.0, false},
        {150.0, std::nan(""), false},
        {inf, 250.0, false},
        {150.0, -inf, false},
    };
    for (const Case& c : cases) {
        auto sample = staticHeightAt(*built.map, c.x, c.y);
        EXPECT_EQ(sample.ok(), c.inside) << "(" << c.x << ", " << c.y << ")";
        if (!sample.ok()) {
            EXPECT_NE(sample.error().message.find(built.path.string()), std::string::npos) << sample.error().message;
            EXPECT_NE(sample.error().message.find("outside"), std::string::npos) << sample.error().message;
        }
    }
}

}  // namespace
}  // namespace terrain
