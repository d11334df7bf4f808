// Height codec of node payloads (docs/map-format.md "Height stream"): the Kobbelt 4-point predictor against
// a floating-point reference, the edge reflection by hand, encode/decode round trips of real node windows
// (lossless and lossy), and corrupt streams that must give errors, never crashes.
#include "quadtree/HeightCodec.h"

#include "MapTestSupport.h"
#include "core/Zlib.h"
#include "quadtree/QuantizedGrid.h"

#include <gtest/gtest.h>

namespace terrain {
namespace {

using test::Bytes;

/// A parent window of random codes over the whole 16-bit range.
std::vector<std::uint16_t> randomWindow(int size, std::uint32_t seed)
{
    std::vector<std::uint16_t> window(static_cast<std::size_t>(size) * size);
    for (std::size_t i = 0; i < window.size(); ++i) {
        window[i] = static_cast<std::uint16_t>(test::hashNoise(seed, static_cast<std::int64_t>(i), 7) & 0xffff);
    }
    return window;
}

/// 0 and 65535 alternating: the largest over- and undershoot the predictor can make.
std::vector<std::uint16_t> checkerWindow(int size)
{
    std::vector<std::uint16_t> window(static_cast<std::size_t>(size) * size);
    for (int y = 0; y < size; ++y) {
        for (int x = 0; x < size; ++x) {
            window[static_cast<std::size_t>(y) * size + x] = ((x + y) & 1) ? 65535 : 0;
        }
    }
    return window;
}

// ---- Prediction ----

TEST(HeightCodecTest, PredictionMatchesFloatReferenceOfTheFourPointRule)
{
    for (int chunk : {3, 5, 9, 17, 33, 65}) {
        const int size = chunk + 2 * kBorder;
        const std::vector<std::vector<std::uint16_t>> parents = {randomWindow(size, 11), randomWindow(size, 12),
                                                                 checkerWindow(size)};
        for (std::size_t p = 0; p < parents.size(); ++p) {
            for (int quadrant = 0; quadrant < 4; ++quadrant) {
                std::vector<std::int32_t> out(parents[p].size());
                predictChildWindow(parents[p], size, chunk, quadrant, out);
                int mismatches = 0;
                for (int cy = 0; cy < size; ++cy) {
                    for (int cx = 0; cx < size; ++cx) {
                        auto expected = test::referencePrediction(parents[p], size, chunk, quadrant, cx, cy);
                        auto actual = out[static_cast<std::size_t>(cy) * size + cx];
                        if (expected != actual && ++mismatches <= 3) {
                            ADD_FAILURE()
                                << "chunk " << chunk << " parent " << p << " quadrant " << quadrant << " child (" << cx
                                << ", " << cy << "): predicted " << actual << ", reference " << expected;
                        }
                    }
                }
                EXPECT_EQ(mismatches, 0) << "chunk " << chunk << " parent " << p << " quadrant " << quadrant;
            }
        }
    }
}

TEST(HeightCodecTest, EvenEvenPredictionsCopyTheParentExactly)
{
    for (int chunk : {3, 17, 65}) {
        const int size = chunk + 2 * kBorder;
        const int half = (chunk - 1) / 2;
        const auto parent = randomWindow(size, 21);
        for (int quadrant = 0; quadrant < 4; ++quadrant) {
            std::vector<std::int32_t> out(parent.size());
            predictChildWindow(parent, size, chunk, quadrant, out);
            for (int v = -kBorder; v < chunk + kBorder; v += 2) {
                for (int u = -kBorder; u < chunk + kBorder; u += 2) {
                    const int px = kBorder + (quadrant & 1) * half + u / 2;
                    const int py = kBorder + (quadrant >> 1) * half + v / 2;
                    ASSERT_EQ(out[static_cast<std::size_t>(v + kBorder) * size + u + kBorder],
                              parent[static_cast<std::size_t>(py) * size + px])
                        << "chunk " << chunk << " quadrant " << quadrant << " child sample (" << u << ", " << v << ")";
                }
            }
        }
    }
}

TEST(HeightCodecTest, LinearParentIsPredictedOnItsPlaneRoundedHalfUp)
{
    // Parent code = 1000 + 3 px + 5 py at parent window index (px, py); the 4-point rule reproduces planes, so a
    // child sample standing at parent position (x, y) gets 1000 + 3 x + 5 y, ties rounded up. Chunk 5, window 9,
    // quadrant 3 (north-east): child window index c stands at parent index 4 + (c - 2) / 2.
    const int chunk = 5, size = 9, quadrant = 3;
    std::vector<std::uint16_t> parent(81);
    for (int y = 0; y < size; ++y) {
        for (int x = 0; x < size; ++x) {
            parent[static_cast<std::size_t>(y) * size + x] = static_cast<std::uint16_t>(1000 + 3 * x + 5 * y);
        }
    }
    std::vector<std::int32_t> out(81);
    predictChildWindow(parent, size, chunk, quadrant, out);
    struct Case {
        int cx, cy;
        std::int32_t expected;
    };
    const Case cases[] = {
        {2, 2, 1032},  // stands on parent (4, 4): copied
        {3, 2, 1034},  // (4.5, 4): 1033.5 rounds up
        {2, 3, 1035},  // (4, 4.5): 1034.5 rounds up
        {3, 3, 1036},  // (4.5, 4.5): exactly 1036
        {0, 0, 1024},  // (3, 3): the border, copied
        {1, 0, 1026},  // (3.5, 3): 1025.5 rounds up
        {7, 8, 1055},  // (6.5, 7): 1054.5 rounds up, the stencil reaching the window's last column
    };
    for (const Case& c : cases) {
        const double x = 4 + (c.cx - 2) / 2.0, y = 4 + (c.cy - 2) / 2.0;
        const auto plane = static_cast<std::int32_t>(std::floor(1000 + 3 * x + 5 * y + 0.5));
        EXPECT_EQ(c.expected, plane) << "hand-computed table entry (" << c.cx << ", " << c.cy << ")";
        EXPECT_EQ(out[static_cast<std::size_t>(c.cy) * size + c.cx], c.expected)
            << "child (" << c.cx << ", " << c.cy << ")";
    }
}

// ---- Edge reflection ----

TEST(HeightCodecTest, FillOutsideReflectsAlongXThenYByHand)
{
    // 5 x 5 window, inside x 2..4, y 0..2; outside samples start as garbage. Rows listed south to north.
    constexpr std::uint16_t G = 0xBEEF;
    std::vector<std::uint16_t> window = {
        G, G, 10,  13, 20,  //
        G, G, 5,   7,  8,   //
        G, G, 100, 90, 60,  //
        G, G, G,   G,  G,   //
        G, G, G,   G,  G,
    };
    // x first: (1, y) = 2 (2, y) - (3, y), (0, y) = 2 (2, y) - (4, y); then y over every column:
    // (x, 3) = 2 (x, 2) - (x, 1), (x, 4) = 2 (x, 2) - (x, 0).
    const std::vector<std::uint16_t> expected = {
        0,   7,   10,  13,  20,   //
        2,   3,   5,   7,   8,    //
        140, 110, 100, 90,  60,   //
        278, 217, 195, 173, 112,  //
        280, 213, 190, 167, 100,
    };
    fillOutside(window, 5, WindowRect{2, 0, 4, 2});
    EXPECT_EQ(window, expected);
}

TEST(HeightCodecTest, FillOutsideOnTheHighSideClampsToSixteenBits)
{
    // 4 x 4 window, inside x 0..2, y 0..2: (3, y) = 2 (2, y) - (1, y), then (x, 3) = 2 (x, 2) - (x, 1).
    constexpr std::uint16_t G = 0xBEEF;
    std::vector<std::uint16_t> window = {
        1,  2,  4,  G,  //
        10, 20, 40, G,  //
        7,  7,  7,  G,  //
        G,  G,  G,  G,
    };
    const std::vector<std::uint16_t> expected = {
        1,  2,  4,  6,   //
        10, 20, 40, 60,  //
        7,  7,  7,  7,   //
        4,  0,  0,  0,   // 14 - 20, 14 - 40 and 14 - 60 clamp to 0
    };
    fillOutside(window, 4, WindowRect{0, 0, 2, 2});
    EXPECT_EQ(window, expected);
}

TEST(HeightCodecTest, FillOutsideClampsLargeReflections)
{
    struct Case {
        std::uint16_t inside[3];  // x = 2, 3, 4
        std::uint16_t expected01[2];
    };
    const Case cases[] = {
        {{65000, 100, 0}, {65535, 65535}},  // 130000 - 0, 130000 - 100: above the range
        {{10, 60000, 5}, {15, 0}},          // 20 - 5 fits; 20 - 60000 below the range
        {{0, 65535, 65535}, {0, 0}},       {{65535, 0, 0}, {65535, 65535}},
        {{300, 200, 100}, {500, 400}},  // an ordinary slope continues
    };
    for (const Case& c : cases) {
        std::vector<std::uint16_t> window(5 * 5, 0xBEEF);
        for (int y = 0; y < 5; ++y) {
            for (int k = 0; k < 3; ++k) {
                window[static_cast<std::size_t>(y) * 5 + 2 + k] = c.inside[k];
            }
        }
        fillOutside(window, 5, WindowRect{2, 0, 4, 4});
        for (int y = 0; y < 5; ++y) {
            EXPECT_EQ(window[static_cast<std::size_t>(y) * 5 + 0], c.expected01[0]) << "inside " << c.inside[0];
            EXPECT_EQ(window[static_cast<std::size_t>(y) * 5 + 1], c.expected01[1]) << "inside " << c.inside[0];
        }
    }
}

// ---- Residual quantizer ----

TEST(HeightCodecTest, QuantizeResidualIsTheNearestMultipleOfTheBin)
{
    for (std::uint32_t bin : {1u, 3u, 5u, 7u, 9u, 21u}) {
        for (std::int32_t r = -70; r <= 70; ++r) {
            // Brute force: the nearest multiple of an odd bin is unique.
            const auto b = static_cast<std::int32_t>(bin);
            std::int32_t best = 0;
            for (std::int32_t k = -100; k <= 100; ++k) {
                if (std::abs(r - k * b) < std::abs(r - best)) {
                    best = k * b;
                }
            }
            EXPECT_EQ(quantizeResidual(r, bin), best) << "residual " << r << " bin " << bin;
        }
    }
}

// ---- Round trips of real node windows ----

struct RoundTripCase {
    const char* name;
    bool rough;
    std::uint32_t bin;
    int chunk;
};

void PrintTo(const RoundTripCase& c, std::ostream* os)
{
    *os << c.name;
}

class HeightCodecRoundTripTest : public ::testing::TestWithParam<RoundTripCase> {};

TEST_P(HeightCodecRoundTripTest, EveryNodeDecodesToItsWindow)
{
    const RoundTripCase& c = GetParam();
    MapHeader header;
    header.chunkSize = static_cast<std::uint32_t>(c.chunk);
    header.textureSize = 3;
    header.levels = 3;
    header.quantizerBin = c.bin;
    const auto gridSize = static_cast<int>(header.gridSize());
    const std::uint32_t margin = (c.bin - 1) / 2;
    // Native values leave `margin` codes free on both sides, as chooseQuantization does for lossy maps.
    HeightField field = c.rough ? test::roughField(gridSize, gridSize, 5, 0, static_cast<int>(65535 - 2 * margin))
                                : test::hillyField(gridSize, gridSize, 5);
    Quantization q;
    q.bin = c.bin;
    q.margin = margin;
    q.nativeMin = 0.0;
    q.nativePerCode = 1.0;
    auto built = QuantizedGrid::build(field, q, static_cast<std::uint32_t>(header.gridSize()));
    ASSERT_TRUE(built.ok()) << built.error().message;
    QuantizedGrid grid = std::move(built.value());
    const std::uint32_t size = grid.size();
    std::vector<std::uint16_t> original(std::size_t{size} * size);
    for (std::uint32_t y = 0; y < size; ++y) {
        for (std::uint32_t x = 0; x < size; ++x) {
            original[std::size_t{y} * size + x] = grid.at(x, y);
        }
    }
    if (c.bin > 1) {
        grid.reconstructLossy(header, c.bin, 1);
        bool lossy = false;
        for (std::uint32_t y = 0; y < size; ++y) {
            for (std::uint32_t x = 0; x < size; ++x) {
                const std::uint16_t before = original[std::size_t{y} * size + x];
                ASSERT_LE(std::abs(int{grid.at(x, y)} - int{before}), static_cast<int>(margin))
                    << "grid sample " << x << ", " << y;
                lossy = lossy || grid.at(x, y) != before;
            }
        }
        EXPECT_TRUE(lossy) << "a bin of " << c.bin << " should change some codes";
    }

    const NodeWindow geometry(header);
    const int w = geometry.size();
    for (int level = 0; level < 3; ++level) {
        const std::uint32_t side = 1u << level;
        const std::uint64_t stride = test::strideAt(header, level);
        const auto last = static_cast<std::int64_t>(header.levelGridSize(level)) - 1;
        for (std::uint32_t y = 0; y < side; ++y) {
            for (std::uint32_t x = 0; x < side; ++x) {
                const NodeId id{level, x, y};
                std::vector<std::uint16_t> window(geometry.sampleCount());
                grid.extractWindow(header, id, window);
                // The window is the level's grid around the node, reflected beyond the terrain's edges.
                for (int cy = 0; cy < w; ++cy) {
                    for (int cx = 0; cx < w; ++cx) {
                        auto expected = test::reflectedCode(
                            [&](std::int64_t gx, std::int64_t gy) {
                                return grid.at(static_cast<std::uint64_t>(gx) * stride,
                                               static_cast<std::uint64_t>(gy) * stride);
                            },
                            last, std::int64_t{x} * (c.chunk - 1) + cx - kBorder,
                            std::int64_t{y} * (c.chunk - 1) + cy - kBorder);
                        ASSERT_EQ(window[static_cast<std::size_t>(cy) * w + cx], expected)
                            << id.toString() << " window sample (" << cx << ", " << cy << ")";
                    }
                }
                std::vector<std::uint16_t> parent;
                if (!id.isRoot()) {
                    parent.resize(geometry.sampleCount());
                    grid.extractWindow(header, id.parent(), parent);
                    // The codec's precondition, checked against the reference predictor: residuals are
                    // multiples of the bin at every coded sample inside the grid.
                    const WindowRect inside = geometry.insideRect(id);
                    for (int cy = inside.y0; cy <= inside.y1; ++cy) {
                        for (int cx = inside.x0; cx <= inside.x1; ++cx) {
                            auto predicted = test::referencePrediction(parent, w, c.chunk, id.quadrant(), cx, cy);
                            auto residual = window[static_cast<std::size_t>(cy) * w + cx] - predicted;
                            ASSERT_EQ(residual % c.bin, 0) << id.toString() << " sample (" << cx << ", " << cy << ")";
                        }
                    }
                }
                auto stream = encodeNodeHeights(geometry, id, window, parent, c.bin);
                std::vector<std::uint16_t> decoded(geometry.sampleCount(), 0xBEEF);
                auto status = decodeNodeHeights(geometry, id, stream, parent, c.bin, decoded);
                ASSERT_TRUE(status.ok()) << id.toString() << ": " << status.error().message;
                ASSERT_EQ(decoded, window) << id.toString();
            }
        }
    }
}

INSTANTIATE_TEST_SUITE_P(
    , HeightCodecRoundTripTest,
    ::testing::Values(RoundTripCase{"SmoothLossless", false, 1, 17}, RoundTripCase{"RoughLossless", true, 1, 17},
                      RoundTripCase{"SmoothBin5", false, 5, 17}, RoundTripCase{"RoughBin5", true, 5, 17},
                      RoundTripCase{"RoughBin5Chunk5", true, 5, 5}, RoundTripCase{"RoughLosslessChunk3", true, 1, 3}),
    [](const auto& paramInfo) { return std::string(paramInfo.param.name); });

TEST(HeightCodecTest, RootOfArbitraryCodesRoundTrips)
{
    // The root has no parent: any window codes, including both ends of the range, come back exactly inside
    // the grid; outside samples come back as the reflection.
    MapHeader header;
    header.chunkSize = 17;
    header.levels = 2;
    const NodeWindow geometry(header);
    const int w = geometry.size();
    auto window = randomWindow(w, 31);
    window[static_cast<std::size_t>(kBorder) * w + kBorder] = 65535;
    window[static_cast<std::size_t>(kBorder + 1) * w + kBorder] = 0;
    auto expected = window;
    fillOutside(expected, w, geometry.insideRect(NodeId::root()));
    auto stream = encodeNodeHeights(geometry, NodeId::root(), window, {}, 1);
    std::vector<std::uint16_t> decoded(geometry.sampleCount(), 0);
    auto status = decodeNodeHeights(geometry, NodeId::root(), stream, {}, 1, decoded);
    ASSERT_TRUE(status.ok()) << status.error().message;
    EXPECT_EQ(decoded, expected);
}

// ---- Corrupt streams ----

/// A node of a small lossless map with its parent window and stream, for mutation tests.
struct CodedNode {
    MapHeader header;
    NodeId id{1, 1, 0};
    std::vector<std::uint16_t> parent;
    Bytes stream;
};

CodedNode codedNode()
{
    CodedNode node;
    node.header.chunkSize = 17;
    node.header.levels = 2;
    const auto gridSize = static_cast<int>(node.header.gridSize());
    HeightField field = test::hillyField(gridSize, gridSize, 9);
    Quantization q;
    auto grid = QuantizedGrid::build(field, q, static_cast<std::uint32_t>(node.header.gridSize()));
    const NodeWindow geometry(node.header);
    std::vector<std::uint16_t> window(geometry.sampleCount());
    node.parent.resize(geometry.sampleCount());
    grid->extractWindow(node.header, node.id, window);
    grid->extractWindow(node.header, NodeId::root(), node.parent);
    node.stream = encodeNodeHeights(geometry, node.id, window, node.parent, 1);
    return node;
}

Status decodeStream(const CodedNode& node, std::span<const std::uint8_t> stream)
{
    const NodeWindow geometry(node.header);
    std::vector<std::uint16_t> window(geometry.sampleCount());
    return decodeNodeHeights(geometry, node.id, stream, node.parent, 1, window);
}

TEST(HeightCodecTest, CorruptStreamsAreErrors)
{
    const CodedNode node = codedNode();
    ASSERT_TRUE(decodeStream(node, node.stream).ok()) << "the unmodified stream must decode";
    const std::uint32_t rawSize = static_cast<std::uint32_t>(test::readLe(node.stream, 0, 4));

    EXPECT_FALSE(decodeStream(node, {}).ok()) << "empty stream";
    for (std::size_t length = 0; length < node.stream.size(); ++length) {
        EXPECT_FALSE(decodeStream(node, std::span(node.stream).first(length)).ok())
            << "truncated to " << length << " bytes";
    }
    // A flipped byte is an error, except the rare flip zlib's Adler-32 cannot see: a changed match distance
    // that copies the same bytes in another order keeps both of its sums (measured: 2 of 292 flips of
    // this stream). The map's CRC-32 over every payload catches those (MapFaultTest); here they must stay
    // rare, and every flip must either fail or decode.
    int undetected = 0;
    for (std::size_t i = 0; i < node.stream.size(); ++i) {
        for (std::uint8_t flip : {std::uint8_t{0x01}, std::uint8_t{0xff}}) {
            Bytes bad = node.stream;
            bad[i] ^= flip;
            undetected += decodeStream(node, bad).ok() ? 1 : 0;
        }
    }
    EXPECT_LE(undetected, static_cast<int>(2 * node.stream.size()) / 50) << "of " << 2 * node.stream.size();
    for (const Bytes& tail : {Bytes{0}, Bytes{0x78, 0x9c}, Bytes(node.stream.begin() + 4, node.stream.end())}) {
        Bytes bad = node.stream;
        bad.insert(bad.end(), tail.begin(), tail.end());
        EXPECT_FALSE(decodeStream(node, bad).ok()) << tail.size() << " trailing bytes";
    }
    for (std::uint32_t size : {rawSize - 1, rawSize + 1, 0u, 3u * 21 * 21 + 1, 0xffffffffu}) {
        Bytes bad = node.stream;
        test::writeLe(bad, 0, size, 4);
        EXPECT_FALSE(decodeStream(node, bad).ok()) << "raw size " << size << " instead of " << rawSize;
    }
}

/// A root height stream of chunk 3 (one level: 3 x 3 coded samples) from hand-made residual bytes.
Bytes rootStream(const Bytes& raw)
{
    Bytes stream(4);
    test::writeLe(stream, 0, raw.size(), 4);
    auto packed = zlibCompress(raw);
    stream.insert(stream.end(), packed.begin(), packed.end());
    return stream;
}

TEST(HeightCodecTest, HandMadeRootStreamsDecodeByTheDocumentedPrediction)
{
    // Residuals in raster order (rows south to north); the root predicts each sample from the previous one in
    // its row, the first of a row from the one below, the very first from 0. Zigzag: 0 -> 0, -1 -> 1, 1 -> 2...
    // residuals 100, +1, -1 / +5, 0, -10 / -5, +50, 0
    const Bytes raw = {0xc8, 0x01, 2, 1, 10, 0, 19, 9, 100, 0};
    MapHeader header;
    header.chunkSize = 3;
    header.levels = 1;
    const NodeWindow geometry(header);
    std::vector<std::uint16_t> window(geometry.sampleCount());
    auto status = decodeNodeHeights(geometry, NodeId::root(), rootStream(raw), {}, 1, window);
    ASSERT_TRUE(status.ok()) << status.error().message;
    const std::uint16_t expected[3][3] = {{100, 101, 100}, {105, 105, 95}, {100, 150, 150}};
    for (int v = 0; v < 3; ++v) {
        for (int u = 0; u < 3; ++u) {
            EXPECT_EQ(window[static_cast<std::size_t>(v + kBorder) * 7 + u + kBorder], expected[v][u])
                << u << ", " << v;
        }
    }
    // With a bin of 3 every residual counts three times.
    status = decodeNodeHeights(geometry, NodeId::root(), rootStream(raw), {}, 3, window);
    ASSERT_TRUE(status.ok()) << status.error().message;
    EXPECT_EQ(window[static_cast<std::size_t>(kBorder) * 7 + kBorder + 2], 300);  // 300 + 3 - 3
}

TEST(HeightCodecTest, MalformedResidualBytesAreErrors)
{
    MapHeader header;
    header.chunkSize = 3;
    header.levels = 1;
    const NodeWindow geometry(header);
    struct Case {
        const char* what;
        Bytes raw;
        bool ok;
    };
    const Case cases[] = {
        {"nine zero residuals", Bytes(9, 0), true},
        {"eight residuals for nine samples", Bytes(8, 0), false},
        {"ten residuals for nine samples", Bytes(10, 0), false},
        {"first sample decodes to -1", {1, 0, 0, 0, 0, 0, 0, 0, 0}, false},
        {"first sample decodes to 65536", {0x80, 0x80, 0x08, 0, 0, 0, 0, 0, 0, 0, 0}, false},
        {"first sample decodes to 65535", {0xfe, 0xff, 0x07, 0, 0, 0, 0, 0, 0, 0, 0}, true},
        {"second sample steps below 0", {0x02, 0x05, 0, 0, 0, 0, 0, 0, 0}, false},
        {"a six-byte varint", {0x80, 0x80, 0x80, 0x80, 0x80, 0x01, 0, 0, 0, 0, 0, 0, 0, 0}, false},
        {"a varint cut off at the end", {0, 0, 0, 0, 0, 0, 0, 0, 0x80}, false},
    };
    for (const Case& c : cases) {
        std::vector<std::uint16_t> window(geometry.sampleCount());
        auto status = decodeNodeHeights(geometry, NodeId::root(), rootStream(c.raw), {}, 1, window);
        EXPECT_EQ(status.ok(), c.ok) << c.what << (status.ok() ? "" : ": " + status.error().message);
    }
}

}  // namespace
}  // namespace terrain
