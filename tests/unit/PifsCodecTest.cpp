// Seed 003's fractal height coding (quadtree/PifsCodec.h): planes are attractors of the fitted transforms,
// every node's stream decodes to exactly what the build stored, a map of real terrain (Jacksboro fault)
// verifies and holds every stored sample of every node within its stored max error (the largest error is
// that bound: it is measured, not guessed), and corrupt streams are clear errors.
#include "quadtree/PifsCodec.h"

#include "MapTestSupport.h"
#include "core/ByteIo.h"
#include "core/Zlib.h"
#include "heightfield/HeightFieldIo.h"
#include "quadtree/MapVerifier.h"

#include <gtest/gtest.h>
#include <cmath>

namespace terrain {
namespace {

bool mentions(const std::string& text, const std::string& what)
{
    return text.find(what) != std::string::npos;
}

/// A header for a 3-level map of chunk `chunk` with every sample valid.
MapHeader smallHeader(int chunk, std::uint32_t levels = 3)
{
    MapHeader h;
    h.chunkSize = static_cast<std::uint32_t>(chunk);
    h.levels = levels;
    h.heightCoding = kHeightCodingPifs;
    h.validWidth = h.validHeight = static_cast<std::uint32_t>(h.gridSize());
    return h;
}

std::vector<NodeId> allNodesAt(int level)
{
    std::vector<NodeId> ids;
    for (std::uint32_t y = 0; y < (1u << level); ++y) {
        for (std::uint32_t x = 0; x < (1u << level); ++x) {
            ids.push_back({level, x, y});
        }
    }
    return ids;
}

TEST(PifsCodecTest, PlanesAreAttractorsOfTheirTransformsWithinOneCode)
{
    // A plane's range blocks are its shrunk domains scaled by 1/2 (the domain spans twice the distance):
    // the fit finds that, and the decoder's iteration converges to the plane from the range means.
    for (int chunk : {9, 17, 65}) {
        const int size = windowSize(chunk);
        const int half = (chunk - 1) / 2;
        const NodeId id{2, 1, 2};  // quadrant 2: west, north half of its parent
        auto plane = [](double u, double v) { return 20000.0 + 7.0 * u - 3.0 * v; };
        std::vector<std::uint16_t> window(static_cast<std::size_t>(size) * size), parent(window.size());
        const int qx = id.quadrant() & 1, qy = id.quadrant() >> 1;
        for (int y = 0; y < size; ++y) {
            for (int x = 0; x < size; ++x) {
                window[static_cast<std::size_t>(y) * size + x] =
                    static_cast<std::uint16_t>(plane(x - kBorder, y - kBorder));
                // Parent sample (x, y) lies at child coordinate 2 (x - kBorder - q half).
                parent[static_cast<std::size_t>(y) * size + x] =
                    static_cast<std::uint16_t>(plane(2.0 * (x - kBorder - qx * half), 2.0 * (y - kBorder - qy * half)));
            }
        }
        const auto transforms = fitPifs(id, chunk, window, parent);
        ASSERT_EQ(transforms.size(), static_cast<std::size_t>((chunk - 1) / 4 * (chunk - 1) / 4));
        std::vector<std::uint16_t> decoded = window;
        iteratePifs(id, chunk, transforms, kPifsIterations, parent, decoded);
        int coded = 0;
        for (int y = 0; y < size; ++y) {
            for (int x = 0; x < size; ++x) {
                const auto i = static_cast<std::size_t>(y) * size + x;
                if (!pifsCodes(id, chunk, x, y)) {
                    EXPECT_EQ(decoded[i], window[i]) << "a fixed sample changed at (" << x << ", " << y << ")";
                    continue;
                }
                ++coded;
                EXPECT_NEAR(decoded[i], window[i], 1.0) << "chunk " << chunk << " at (" << x << ", " << y << ")";
            }
        }
        // Interior samples minus the parent's even-even ones.
        EXPECT_EQ(coded, (chunk - 2) * (chunk - 2) - (half - 1) * (half - 1)) << "chunk " << chunk;
    }
}

TEST(PifsCodecTest, TheRootIsStoredExactly)
{
    // The root has no parent to take domains from, and its own fit coarse terrain badly (PifsCodec.h): no
    // sample of it is fractal-coded.
    for (int y = 0; y < windowSize(17); ++y) {
        for (int x = 0; x < windowSize(17); ++x) {
            EXPECT_FALSE(pifsCodes(NodeId::root(), 17, x, y));
        }
    }
    EXPECT_TRUE(fitPifs(NodeId::root(), 17, std::vector<std::uint16_t>(21 * 21, 5), {}).empty());
}

/// A pyramid of a rough 3-level 65^2 grid (chunk 17), every node present.
struct SmallPyramid {
    MapHeader header = smallHeader(17);
    QuantizedGrid grid = makeGrid(header);
    PifsPyramid pyramid;

    SmallPyramid() : pyramid(build(header, grid)) {}
    static QuantizedGrid makeGrid(const MapHeader& h)
    {
        auto grid = QuantizedGrid::create(static_cast<std::uint32_t>(h.gridSize()));
        EXPECT_TRUE(grid.ok());
        return std::move(grid.value());
    }
    static PifsPyramid build(const MapHeader& h, QuantizedGrid& g)
    {
        const auto field =
            test::roughField(static_cast<int>(h.gridSize()), static_cast<int>(h.gridSize()), 31, 0, 4000);
        for (int y = 0; y < field.height; ++y) {
            for (int x = 0; x < field.width; ++x) {
                g.at(static_cast<std::uint64_t>(x), static_cast<std::uint64_t>(y)) =
                    static_cast<std::uint16_t>(field.at(x, y) + 1000);
            }
        }
        return PifsPyramid::build(h, g, allNodesAt, 2, 4);
    }
};

TEST(PifsCodecTest, EveryStreamDecodesToWhatThePyramidStores)
{
    const SmallPyramid p;
    const NodeWindow geometry(p.header);
    std::uint32_t worst = 0;
    for (int level = 0; level < 3; ++level) {
        for (const NodeId& id : allNodesAt(level)) {
            std::vector<std::uint16_t> stored(geometry.sampleCount()), parent, decoded(geometry.sampleCount());
            p.pyramid.extractWindow(id, stored);
            if (!id.isRoot()) {
                parent.resize(geometry.sampleCount());
                p.pyramid.extractWindow(id.parent(), parent);
            }
            auto status = decodePifsHeights(geometry, id, p.pyramid.stream(id), parent, decoded);
            ASSERT_TRUE(status.ok()) << id.toString() << ": " << status.error().message;
            EXPECT_EQ(decoded, stored) << id.toString();
            // The stored error against the grid, measured here from the grid's own samples.
            const WindowRect inside = geometry.insideRect(id);
            const int stride = 1 << (2 - level);
            std::uint32_t nodeWorst = 0;
            for (int y = inside.y0; y <= inside.y1; ++y) {
                for (int x = inside.x0; x <= inside.x1; ++x) {
                    const std::int64_t gx = (std::int64_t{id.x} * 16 - kBorder + x) * stride;
                    const std::int64_t gy = (std::int64_t{id.y} * 16 - kBorder + y) * stride;
                    const int code = p.grid.at(static_cast<std::uint64_t>(gx), static_cast<std::uint64_t>(gy));
                    nodeWorst = std::max<std::uint32_t>(
                        nodeWorst,
                        static_cast<std::uint32_t>(std::abs(code - stored[static_cast<std::size_t>(y) * 21 + x])));
                }
            }
            EXPECT_EQ(p.pyramid.errorCodes(id), nodeWorst) << id.toString();
            worst = std::max(worst, nodeWorst);
        }
    }
    EXPECT_EQ(p.pyramid.maxErrorCodes(), worst);
    EXPECT_EQ(p.pyramid.errorCodes(NodeId::root()), 0u) << "the root is stored exactly";
    EXPECT_GT(worst, 0u) << "a rough field is not coded losslessly by 4 x 4 fractal blocks";
}

TEST(PifsCodecTest, CorruptStreamsAreClearErrors)
{
    const SmallPyramid p;
    const NodeWindow geometry(p.header);
    const NodeId id{2, 1, 2};
    std::vector<std::uint16_t> parent(geometry.sampleCount()), window(geometry.sampleCount());
    p.pyramid.extractWindow(id.parent(), parent);
    const auto& stream = p.pyramid.stream(id);
    const auto rawSize = static_cast<std::uint32_t>(test::readLe(stream, 0, 4));
    const auto raw = zlibDecompress(std::span(stream).subspan(4), rawSize).value();
    auto pack = [](const test::Bytes& bytes) {
        test::Bytes out;
        ByteWriter(out).put(static_cast<std::uint32_t>(bytes.size()));
        const auto packed = zlibCompress(bytes);
        out.insert(out.end(), packed.begin(), packed.end());
        return out;
    };
    auto varintBytes = [](std::uint32_t v) {
        test::Bytes out;
        ByteWriter(out).putVarint(v);
        return out;
    };
    // Transform 0 starts at raw[1]: varint(domain * 8 + isometry), the scale byte, varint(zigzag(mean)).
    std::size_t domainEnd = 1;
    while (raw[domainEnd] & 0x80) {
        ++domainEnd;
    }
    ++domainEnd;
    auto replace = [&](std::size_t from, std::size_t to, const test::Bytes& with) {
        test::Bytes out(raw.begin(), raw.begin() + static_cast<std::ptrdiff_t>(from));
        out.insert(out.end(), with.begin(), with.end());
        out.insert(out.end(), raw.begin() + static_cast<std::ptrdiff_t>(to), raw.end());
        return out;
    };
    std::size_t meanEnd = domainEnd + 1;
    while (raw[meanEnd] & 0x80) {
        ++meanEnd;
    }
    ++meanEnd;
    // The last correction: the bytes after the last varint terminator before the end.
    std::size_t lastStart = raw.size() - 1;
    while (lastStart > 0 && (raw[lastStart - 1] & 0x80)) {
        --lastStart;
    }
    const std::uint32_t domains = 9 + 49;  // (16 - 8) / 4 + 1 = 3 per side own, 7 x 7 from the parent
    test::Bytes zeroIterations = raw, tooManyIterations = raw;
    zeroIterations[0] = 0;
    tooManyIterations[0] = kPifsMaxIterations + 1;
    test::Bytes badScale = raw;
    badScale[domainEnd] = 2 * kPifsMaxScale + 1;
    test::Bytes truncated(raw.begin(), raw.end() - 1);
    test::Bytes longer = raw;
    longer.push_back(0);
    struct Case {
        const char* name;
        test::Bytes stream;
        std::string mentions;
    };
    const Case cases[] = {
        {"empty", {}, "header is invalid"},
        {"huge raw size",
         [&] {
             test::Bytes b = stream;
             test::writeLe(b, 0, 0x7fffffff, 4);
             return b;
         }(),
         "header is invalid"},
        {"not zlib",
         [&] {
             test::Bytes b(stream.begin(), stream.begin() + 4);
             b.insert(b.end(), 40, 0x5a);
             return b;
         }(),
         "fractal height stream: "},
        {"zero iterations", pack(zeroIterations), "asks for 0 iterations"},
        {"too many iterations", pack(tooManyIterations), "asks for 65 iterations"},
        {"domain out of range", pack(replace(1, domainEnd, varintBytes(domains * 8))), "domain 58 of 58"},
        {"scale code out of range", pack(badScale), "scale code 31"},
        {"mean out of range", pack(replace(domainEnd + 1, meanEnd, varintBytes(zigzagEncode(70000)))), "mean 70000"},
        {"truncated", pack(truncated), "ends early"},
        {"bytes left over", pack(longer), "1 bytes left over"},
        {"correction out of range", pack(replace(lastStart, raw.size(), varintBytes(zigzagEncode(70000)))),
         "outside the 16-bit range"},
    };
    for (const Case& c : cases) {
        auto status = decodePifsHeights(geometry, id, c.stream, parent, window);
        ASSERT_FALSE(status.ok()) << c.name;
        EXPECT_TRUE(mentions(status.error().message, c.mentions))
            << c.name << ": '" << status.error().message << "' does not mention '" << c.mentions << "'";
    }
    // And the untouched stream still decodes: the cases broke what they name, nothing else.
    EXPECT_TRUE(decodePifsHeights(geometry, id, pack(raw), parent, window).ok());
}

TEST(PifsCodecTest, HeadersOfFractalMapsMustHaveBinOneAndChunksOfNine)
{
    test::ScratchDir dir;
    BuildOptions options = test::testOptions(17);
    options.heightCoding = kHeightCodingPifs;
    auto report = buildMap(test::hillyField(33, 33), options, dir / "h.map");
    ASSERT_TRUE(report.ok()) << report.error().message;
    const MapHeader good = report->header;
    ASSERT_TRUE(decodeHeader(encodeHeader(good), "h.map").ok());
    struct Case {
        const char* name;
        std::function<void(MapHeader&)> change;
        std::string mentions;
    };
    const Case cases[] = {
        {"bin 3", [](MapHeader& h) { h.quantizerBin = 3; }, "fractal height coding with quantizer bin 3"},
        {"chunk 5", [](MapHeader& h) { h.chunkSize = 5; }, "chunks of at least 9 samples"},
        {"coding 3", [](MapHeader& h) { h.heightCoding = 3; }, "unknown height coding 3"},
    };
    for (const Case& c : cases) {
        MapHeader h = good;
        c.change(h);
        auto decoded = decodeHeader(encodeHeader(h), "h.map");
        ASSERT_FALSE(decoded.ok()) << c.name;
        EXPECT_TRUE(mentions(decoded.error().message, c.mentions)) << c.name << ": " << decoded.error().message;
    }
}

TEST(PifsCodecTest, RealTerrainMapVerifiesAndEveryStoredSampleIsWithinTheStoredMaxError)
{
    // Jacksboro fault DEM, 403 x 344 at 30 m, chunks of 17: 6 levels.
    test::ScratchDir dir;
    auto field = readHeightField(test::testDataPath("jacksboro_fault_dem_403x344.png"));
    ASSERT_TRUE(field.ok()) << field.error().message;
    const HeightField input = field.value();
    BuildOptions options = test::testOptions(17, 2);
    options.spacing = 30.0;
    options.heightCoding = kHeightCodingPifs;
    auto report = buildMap(std::move(field.value()), options, dir / "pifs.map");
    ASSERT_TRUE(report.ok()) << report.error().message;
    auto map = test::openMap(dir / "pifs.map");
    ASSERT_TRUE(map);
    const MapHeader& h = map->header();
    EXPECT_EQ(h.heightCoding, kHeightCodingPifs);
    const auto problems = verifyMap(*map);
    EXPECT_TRUE(problems.empty()) << problems.front();
    auto tree = test::decodeTree(*map);
    ASSERT_TRUE(tree.ok()) << tree.error().message;
    const int n = static_cast<int>(h.chunkSize);
    double worst = 0.0, leafSum = 0.0;
    std::size_t leafSamples = 0;
    for (const DirectoryEntry& entry : map->directory()) {
        const StaticNode& node = *tree->find(entry.id);
        const std::uint64_t stride = test::strideAt(h, entry.id.level);
        const auto last = static_cast<std::int64_t>(h.levelGridSize(entry.id.level)) - 1;
        for (int v = -kBorder; v < n + kBorder; ++v) {
            for (int u = -kBorder; u < n + kBorder; ++u) {
                const std::int64_t gx = std::int64_t{entry.id.x} * (n - 1) + u;
                const std::int64_t gy = std::int64_t{entry.id.y} * (n - 1) + v;
                if (gx < 0 || gy < 0 || gx > last || gy > last) {
                    continue;
                }
                const double expected = test::paddedNative(input, gx * static_cast<std::int64_t>(stride),
                                                           gy * static_cast<std::int64_t>(stride));
                const double error = std::abs(h.heightOf(test::windowCode(h, node, u, v)) - expected);
                ASSERT_LE(error, h.maxErrorBound + 1e-9) << entry.id.toString() << " sample (" << u << ", " << v << ")";
                worst = std::max(worst, error);
                if (!entry.hasChildren && u >= 0 && v >= 0 && u < n && v < n) {
                    leafSum += error;
                    ++leafSamples;
                }
            }
        }
    }
    EXPECT_NEAR(worst, h.maxErrorBound, 1e-9) << "the stored bound is the measured largest error";
    const double leafMean = leafSum / static_cast<double>(leafSamples);
    // Pinned quality: with 17-sample chunks (16 ranges, 9 own domains a node) and 6 levels whose errors the
    // leaves inherit at their even samples, the fractal leaves lie 6.0 m from the DEM on average (measured).
    EXPECT_LT(leafMean, 7.5) << "mean leaf error " << leafMean << " m, largest " << worst << " m";
}

}  // namespace
}  // namespace terrain
