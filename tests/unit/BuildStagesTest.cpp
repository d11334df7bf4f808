// buildMap's pure stages (quadtree/BuildStages.h): the option checks in their order, the split level, the
// memory plan's decisions and advice, and the squares marked as holding no-data samples, each against a
// brute-force reference or the documented contract.
#include "quadtree/BuildStages.h"

#include "heightfield/GdalRaster.h"
#include "quadtree/QuantizedGrid.h"

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <vector>

namespace terrain {
namespace {

HeightField sized(int width, int height)
{
    HeightField info;
    info.width = width;
    info.height = height;
    return info;
}

/// The header planMemory reads: chunk size, levels covering width x height, the valid size.
MapHeader headerOf(int width, int height, int chunkSize)
{
    MapHeader header;
    header.chunkSize = static_cast<std::uint32_t>(chunkSize);
    header.levels = 1;
    while (header.gridSize() < static_cast<std::uint64_t>(std::max(width, height))) {
        ++header.levels;
    }
    header.validWidth = static_cast<std::uint32_t>(width);
    header.validHeight = static_cast<std::uint32_t>(height);
    return header;
}

bool mentions(const std::string& text, const std::string& part)
{
    return text.find(part) != std::string::npos;
}

TEST(BuildStagesTest, OptionChecksNameTheFirstBadOptionInOrder)
{
    struct Case {
        const char* what;
        std::function<void(BuildOptions&)> set;
        int width;
        std::string mentions;  ///< empty: accepted
    };
    const Case cases[] = {
        {"defaults", [](BuildOptions&) {}, 2, ""},
        {"chunk 64", [](BuildOptions& o) { o.chunkSize = 64; }, 9, "chunk size 64 must be 2^k+1"},
        {"chunk 2049", [](BuildOptions& o) { o.chunkSize = 2049; }, 9, "chunk size 2049"},
        {"chunk first", [](BuildOptions& o) { o.chunkSize = 4, o.threads = 0; }, 1, "chunk size 4"},
        {"texture 0 follows a bad chunk", [](BuildOptions& o) { o.chunkSize = 3; }, 9, ""},
        {"texture 100", [](BuildOptions& o) { o.textureSize = 100; }, 9, "texture size 100"},
        {"texture too large", [](BuildOptions& o) { o.textureSize = kMaxTextureSize * 2 - 1; }, 9, "texture size"},
        {"threads 0", [](BuildOptions& o) { o.threads = 0; }, 9, "thread count 0 must be at least 1"},
        {"threads -5", [](BuildOptions& o) { o.threads = -5; }, 9, "thread count -5"},
        {"codec 7", [](BuildOptions& o) { o.heightCoding = 7; }, 9, "unknown height coding 7"},
        {"pifs with max error", [](BuildOptions& o) { o.heightCoding = kHeightCodingPifs, o.maxError = 1; }, 9,
         "--max-error has no effect with --height-codec pifs"},
        {"pifs chunk 5", [](BuildOptions& o) { o.heightCoding = kHeightCodingPifs, o.chunkSize = 5; }, 9,
         "chunk size of at least 9"},
        {"pifs chunk 9", [](BuildOptions& o) { o.heightCoding = kHeightCodingPifs, o.chunkSize = 9; }, 9, ""},
        {"1 x 9 input", [](BuildOptions&) {}, 1, "height field is 1x9; at least 2x2"},
        {"options before the input", [](BuildOptions& o) { o.threads = 0; }, 1, "thread count 0"},
    };
    for (const Case& c : cases) {
        BuildOptions options;
        c.set(options);
        const Status status = checkBuildOptions(options, sized(c.width, 9));
        if (c.mentions.empty()) {
            EXPECT_TRUE(status.ok()) << c.what << ": " << status.error().message;
        } else {
            ASSERT_FALSE(status.ok()) << c.what;
            EXPECT_TRUE(mentions(status.error().message, c.mentions)) << c.what << ": " << status.error().message;
        }
    }
}

TEST(BuildStagesTest, SplitLevelIsTheShallowestFromThreeWithSubtreesWithin4096Samples)
{
    for (int chunk : {3, 9, 65, 257, 1025}) {
        for (std::uint32_t levels = 1; levels <= 20; ++levels) {
            MapHeader header;
            header.chunkSize = static_cast<std::uint32_t>(chunk);
            header.levels = levels;
            // Brute force: the least level from min(3, levels - 1) whose square is within 4096 samples, or
            // the finest level.
            const int finest = static_cast<int>(levels) - 1;
            int expected = finest;
            for (int s = std::min(3, finest); s < finest; ++s) {
                if ((std::uint64_t(chunk - 1) << (finest - s)) <= 4096) {
                    expected = s;
                    break;
                }
            }
            EXPECT_EQ(splitLevel(header), expected) << "chunk " << chunk << ", levels " << levels;
        }
    }
}

/// The documented in-memory need: the input (unless held), its codes, the grid, and 1 (+80) bytes a leaf.
std::uint64_t inMemoryBytes(const MapHeader& header, const MemoryRequest& request)
{
    const std::uint64_t samples = std::uint64_t{header.validWidth} * header.validHeight;
    const std::uint64_t leaves = std::uint64_t{1} << (2 * (header.levels - 1));
    return (request.sourceHeld ? 0 : samples * 4) + samples * 2 +
           QuantizedGrid::storageBytes(static_cast<std::uint32_t>(header.gridSize())) +
           leaves * (request.roughness ? 81 : 1);
}

TEST(BuildStagesTest, PlanHoldsTheBuildInMemoryExactlyWhenItFitsTheBudget)
{
    struct Case {
        int width, height, chunk;
        bool held, roughness;
    };
    const Case cases[] = {{1000, 900, 17, false, true},
                          {1000, 900, 17, true, false},
                          {8193, 8193, 65, false, true},
                          {2, 2, 3, false, false},
                          {5000, 3, 33, true, true}};
    auto ignore = [](const std::string&) {};
    for (const Case& c : cases) {
        SCOPED_TRACE(std::to_string(c.width) + "x" + std::to_string(c.height));
        const MapHeader header = headerOf(c.width, c.height, c.chunk);
        MemoryRequest request{0, 4, c.held, c.roughness, false, false};
        const std::uint64_t need = inMemoryBytes(header, request);
        request.budget = need;
        auto plan = planMemory(header, request, ignore);
        ASSERT_TRUE(plan.ok()) << plan.error().message;
        EXPECT_TRUE(plan->inMemory);
        EXPECT_EQ(plan->threads, 4) << "in memory, every thread asked for";
        EXPECT_EQ(plan->coreRows, 0);
        request.forceOutOfCore = true;
        request.budget = std::uint64_t{1} << 40;
        plan = planMemory(header, request, ignore);
        ASSERT_TRUE(plan.ok()) << plan.error().message;
        EXPECT_FALSE(plan->inMemory) << "--out-of-core";
        request.forceOutOfCore = false;
        request.budget = need - 1;
        plan = planMemory(header, request, ignore);
        if (plan.ok()) {
            EXPECT_FALSE(plan->inMemory) << "one byte short";
        }
        request.pifs = true;
        plan = planMemory(header, request, ignore);
        ASSERT_FALSE(plan.ok());
        EXPECT_TRUE(mentions(plan.error().message, "--height-codec pifs builds in memory")) << plan.error().message;
    }
}

TEST(BuildStagesTest, OutOfCorePlanTakesTheThreadsThatFitAndAdvisesTheLeastBudgetThatWorks)
{
    struct Case {
        int width, height, chunk, threads;
    };
    const Case cases[] = {{1000, 900, 17, 2}, {8193, 8193, 65, 8}, {20000, 300, 33, 3}, {300, 20000, 129, 4}};
    for (const Case& c : cases) {
        SCOPED_TRACE(std::to_string(c.width) + "x" + std::to_string(c.height) + " on " + std::to_string(c.threads));
        const MapHeader header = headerOf(c.width, c.height, c.chunk);
        int lastThreads = 0;
        bool refusedBefore = true;
        for (std::uint64_t mib = 1; mib <= 2048; mib += mib < 64 ? 1 : 16) {
            std::vector<std::string> said;
            const MemoryRequest request{mib << 20, c.threads, false, true, false, true};
            auto plan = planMemory(header, request, [&](const std::string& m) { said.push_back(m); });
            if (!plan.ok()) {
                ASSERT_TRUE(refusedBefore) << mib << " MiB refused after a smaller budget was accepted";
                const std::string& message = plan.error().message;
                const std::size_t at = message.find("--memory ");
                ASSERT_NE(at, std::string::npos) << message;
                const std::uint64_t advised = std::stoull(message.substr(at + 9));
                EXPECT_GT(advised, mib) << message;
                // Following the advice works; a MiB less does not.
                auto advisedPlan =
                    planMemory(header, {advised << 20, c.threads, false, true, false, true}, [](auto&) {});
                EXPECT_TRUE(advisedPlan.ok()) << advised << " MiB: " << advisedPlan.error().message;
                auto lessPlan =
                    planMemory(header, {(advised - 1) << 20, c.threads, false, true, false, true}, [](auto&) {});
                EXPECT_FALSE(lessPlan.ok()) << advised - 1 << " MiB";
                continue;
            }
            refusedBefore = false;
            EXPECT_FALSE(plan->inMemory);
            EXPECT_GE(plan->threads, 1);
            EXPECT_LE(plan->threads, c.threads);
            EXPECT_GE(plan->threads, lastThreads) << mib << " MiB: more budget, never fewer threads";
            lastThreads = plan->threads;
            EXPECT_EQ(said.size(), plan->threads < c.threads ? 1u : 0u) << mib << " MiB";
            if (!said.empty()) {
                EXPECT_TRUE(mentions(said[0], "building on " + std::to_string(plan->threads) + " thread(s) of the " +
                                                  std::to_string(c.threads) + " asked"))
                    << said[0];
            }
            const int cells = c.chunk - 1;
            EXPECT_EQ(plan->coreRows % cells, 0) << "bands of whole leaf rows";
            EXPECT_GE(plan->coreRows, std::max(cells, 256 / cells * cells));
            EXPECT_LE(plan->coarseShift, QuantizedGrid::kTileShift);
            EXPECT_GT(plan->estimatedBytes, 0u);
            EXPECT_LE(plan->estimatedBytes, mib << 20) << "the plan keeps within the budget";
            // Reading through GDAL adds its block cache, as configureGdalReading sizes it for the budget.
            MemoryRequest gdal = request;
            gdal.threads = plan->threads;
            gdal.gdalCache = true;
            auto throughGdal = planMemory(header, gdal, [](auto&) {});
            if (throughGdal.ok() && throughGdal->threads == plan->threads) {
                EXPECT_EQ(throughGdal->estimatedBytes - plan->estimatedBytes, gdalCacheBytesFor(mib << 20));
            }
        }
        EXPECT_EQ(lastThreads, c.threads) << "2 GiB holds every thread";
    }
}

TEST(BuildStagesTest, FilledSquaresAreThoseWhoseClosedSquareHoldsAFlaggedSample)
{
    std::mt19937 random(7);
    struct Case {
        int width, height, cells, leavesPerSide;
        double density;
    };
    const Case cases[] = {
        {9, 9, 8, 2, 0.02}, {17, 9, 4, 8, 0.05}, {33, 40, 16, 4, 0.01}, {5, 5, 2, 4, 0.5}, {40, 33, 8, 8, 0.0}};
    for (const Case& c : cases) {
        std::bernoulli_distribution flag(c.density);
        std::vector<std::uint8_t> mask(static_cast<std::size_t>(c.width) * c.height);
        for (auto& m : mask) {
            m = flag(random) ? 1 : 0;
        }
        mask[0] = 1;  // a corner: its one square
        // Bands of rows as the out-of-core passes give them: each band's mask starts some rows above its core.
        std::vector<std::uint8_t> squares(static_cast<std::size_t>(c.leavesPerSide) * c.leavesPerSide, 0);
        std::uint64_t counted = 0;
        for (int core0 = 0; core0 < c.height; core0 += 7) {
            const int core1 = std::min(c.height, core0 + 7);
            const int row0 = std::max(0, core0 - 3);
            std::span<const std::uint8_t> band(mask.data() + static_cast<std::size_t>(row0) * c.width,
                                               static_cast<std::size_t>(c.height - row0) * c.width);
            counted += markFilledSquares(band, c.width, row0, core0, core1, c.cells,
                                         static_cast<std::uint64_t>(c.leavesPerSide), squares);
        }
        std::uint64_t flagged = 0;
        for (auto m : mask) {
            flagged += m;
        }
        EXPECT_EQ(counted, flagged);
        for (int sy = 0; sy < c.leavesPerSide; ++sy) {
            for (int sx = 0; sx < c.leavesPerSide; ++sx) {
                bool expected = false;
                for (int y = sy * c.cells; y <= (sy + 1) * c.cells && y < c.height; ++y) {
                    for (int x = sx * c.cells; x <= (sx + 1) * c.cells && x < c.width; ++x) {
                        expected = expected || mask[static_cast<std::size_t>(y) * c.width + x];
                    }
                }
                EXPECT_EQ(squares[static_cast<std::size_t>(sy) * c.leavesPerSide + sx] != 0, expected)
                    << c.width << "x" << c.height << " square " << sx << ", " << sy;
            }
        }
    }
    std::vector<std::uint8_t> squares(4, 0);
    EXPECT_EQ(markFilledSquares({}, 9, 0, 0, 9, 8, 2, squares), 0u) << "no mask: nothing was filled";
    EXPECT_EQ(squares, std::vector<std::uint8_t>(4, 0));
}

}  // namespace
}  // namespace terrain
