// buildMap's pure stages: option checks, the memory plan (docs/design.md, "Out-of-core prep") and the
// squares that held no-data samples.
#include "quadtree/BuildStages.h"

#include "core/Memory.h"
#include "heightfield/GdalRaster.h"
#include "quadtree/PifsCodec.h"
#include "quadtree/QuantizedGrid.h"

#include <algorithm>
#include <string>

namespace terrain {

int effectiveTextureSize(const BuildOptions& options)
{
    return options.textureSize == 0 ? options.chunkSize : options.textureSize;
}

Status checkBuildOptions(const BuildOptions& options, const HeightField& info)
{
    if (!isValidChunkSize(options.chunkSize)) {
        return makeError("chunk size ", options.chunkSize, " must be 2^k+1 between 3 and ", kMaxChunkSize,
                         " (e.g. 33, 65, 129)");
    }
    const int textureSize = effectiveTextureSize(options);
    if (!isPowerOfTwoPlusOne(textureSize) || textureSize > kMaxTextureSize) {
        return makeError("texture size ", textureSize, " must be 2^k+1 between 3 and ", kMaxTextureSize,
                         " (e.g. 65, 129, 257)");
    }
    if (options.threads < 1) {
        return makeError("thread count ", options.threads, " must be at least 1");
    }
    const bool pifs = options.heightCoding == kHeightCodingPifs;
    if (!pifs && options.heightCoding != kHeightCodingKobbeltResidual) {
        return makeError("unknown height coding ", options.heightCoding);
    }
    if (pifs && options.maxError > 0) {
        return makeError(
            "--max-error has no effect with --height-codec pifs: the fractal code's error is what it "
            "measures, stored in the map (use the residual codec for a bound)");
    }
    if (pifs && options.chunkSize < 9) {
        return makeError(
            "--height-codec pifs needs a chunk size of at least 9 (4 x 4 range blocks and 8 x 8 "
            "domains), not ",
            options.chunkSize);
    }
    if (info.width < 2 || info.height < 2) {
        return makeError("height field is ", info.width, "x", info.height, "; at least 2x2 samples are needed");
    }
    return {};
}

int splitLevel(const MapHeader& header)
{
    const int levels = static_cast<int>(header.levels);
    int split = std::min(3, levels - 1);
    while (split < levels - 1 && (std::uint64_t{header.chunkSize - 1} << (levels - 1 - split)) > 4096) {
        ++split;
    }
    return split;
}

namespace {

/// The anonymous memory of prep with no input to speak of: the code's heap (GDAL, PROJ, the material and the
/// detail synthesizer). Measured: prep's anonymous peak on tests/data/etopo5_karakoram_129.png out of core,
/// 6 MiB (RssAnon sampled every 50 ms).
constexpr std::uint64_t kProcessBaseBytes = std::uint64_t{6} << 20;
/// Bytes per sample of a band's window while a pass holds it: the floats kept (4), the reader's own copy (4:
/// ElevationRaster::readRows reads into a buffer before flagging no-data) and the fill's no-data mask (1).
constexpr std::uint64_t kBandBytesPerSample = 9;
/// glibc's largest dynamic mmap threshold (64-bit): a freed block below it stays in the heap. The reader's copy
/// of a band is allocated and freed once a band. Measured on an 8193^2 float32 UTM GeoTIFF: the copy of the
/// last, shorter band (30 MiB at --memory 256M, 10 MiB at 400M) stayed resident to the end, the full bands'
/// (43 and 67 MiB) did not; on a 4097^2 crop of it at 160M, whose full band's copy (26 MiB) stays, a pass
/// held three band-sized buffers at once (104 MiB).
constexpr std::uint64_t kAllocatorKeepsBelow = std::uint64_t{32} << 20;
/// A worker thread's bytes per sample of its subtree's square (borders included): its encoded nodes, node
/// windows, textures and detail synthesis. Measured over the node phase: a second thread added 10 MiB on a
/// 7263x9104 GeoTIFF reprojected from geographic at --memory 400M (subtrees of 2176^2 samples with their
/// borders: 2.2 bytes a sample), and 2.2 to 2.8 MiB on the 8193^2 one (1152^2: 1.7 to 2.2 bytes a sample).
constexpr double kThreadBytesPerSample = 2.5;

/// The out-of-core build's anonymous memory at its peak, for a budget (its band grows with it) and a number
/// of threads: the larger of the passes (the band's window at kBandBytesPerSample and a copy the allocator
/// keeps) and the node building (the copy kept and the worker threads' subtrees), over the process's base, GDAL's block
/// cache when the source reads through it, the per-map structures (a byte and the roughness sums per leaf, the far
/// fill's block means, the coarse lattice) and the reader's copies the allocator keeps.
class OutOfCoreNeed {
public:
    OutOfCoreNeed(const MapHeader& header, std::uint64_t fixedBytes, int coarseShift, bool gdalCache)
        : mCells(static_cast<int>(header.chunkSize) - 1),
          mWidth(header.validWidth),
          mHeight(header.validHeight),
          mGdalCache(gdalCache),
          mFixedBytes(kProcessBaseBytes + fixedBytes +
                      std::uint64_t{header.validWidth} * header.validHeight / (kFillBlock * kFillBlock) * 16 +
                      QuantizedGrid::coarseLatticeBytes(static_cast<std::uint32_t>(header.gridSize()), coarseShift))
    {
        const auto split = static_cast<std::uint32_t>(splitLevel(header));
        const std::uint64_t side = std::min<std::uint64_t>(
            header.gridSize(), (std::uint64_t{header.chunkSize - 1} << (header.levels - 1 - split)) +
                                   2 * static_cast<std::uint64_t>(mCells));
        mPerThread = static_cast<std::uint64_t>(kThreadBytesPerSample * static_cast<double>(side * side));
    }

    /// The rows a band produces: a quarter of the budget for the band at 6 bytes a sample, at least a leaf row
    /// and 256 rows, at most the leaf rows that cover the input (one band then reads it all; a budget of any
    /// size stays within int).
    int coreRowsFor(std::uint64_t budget) const
    {
        const std::uint64_t bandRows = std::max<std::uint64_t>(budget / 4 / (mWidth * 6), 1);
        const std::uint64_t cells = static_cast<std::uint64_t>(mCells);
        const std::uint64_t inputLeafRows = std::max<std::uint64_t>((mHeight + cells - 1) / cells, 1);
        const std::uint64_t leafRowsPerBand =
            std::min(inputLeafRows,
                     std::max<std::uint64_t>({bandRows > 2 * kBandMargin ? (bandRows - 2 * kBandMargin) / cells : 0,
                                              256 / cells, std::uint64_t{1}}));
        return static_cast<int>(leafRowsPerBand * cells);
    }

    /// Bytes the build holds at its peak within `budget` on `threads` threads.
    std::uint64_t bytes(std::uint64_t budget, int threads) const
    {
        const std::uint64_t coreRows = static_cast<std::uint64_t>(coreRowsFor(budget));
        const std::uint64_t windowRows = std::min<std::uint64_t>(mHeight, coreRows + 2 * kBandMargin);
        const std::uint64_t lastCore = mHeight - (mHeight - 1) / coreRows * coreRows;
        // The reader's copies in bytes: a full band's, and the last band's in the first pass (no margin) and the
        // second (its margin above it).
        const std::uint64_t fullCopy = windowRows * mWidth * 4;
        const std::uint64_t lastCopy = std::min<std::uint64_t>(mHeight, lastCore + kBandMargin) * mWidth * 4;
        const std::uint64_t firstLastCopy = lastCore * mWidth * 4;
        std::uint64_t kept = fullCopy < kAllocatorKeepsBelow ? fullCopy : 0;
        for (std::uint64_t copy : {lastCopy, firstLastCopy}) {
            kept = std::max(kept, copy < kAllocatorKeepsBelow ? copy : 0);
        }
        const std::uint64_t passes = windowRows * mWidth * kBandBytesPerSample + kept;
        const std::uint64_t nodes = kept + static_cast<std::uint64_t>(threads) * mPerThread;
        return mFixedBytes + (mGdalCache ? gdalCacheBytesFor(budget) : 0) + std::max(passes, nodes);
    }

private:
    int mCells;
    std::uint64_t mWidth;
    std::uint64_t mHeight;
    bool mGdalCache;
    std::uint64_t mFixedBytes;
    std::uint64_t mPerThread = 0;
};

}  // namespace

Expected<MemoryPlan> planMemory(const MapHeader& header, const MemoryRequest& request,
                                const std::function<void(const std::string&)>& warn)
{
    const std::uint32_t width = header.validWidth, height = header.validHeight;
    const auto gridSize = static_cast<std::uint32_t>(header.gridSize());
    const std::uint64_t leavesPerSide = std::uint64_t{1} << (header.levels - 1);
    const std::uint64_t budget = request.budget;
    const std::uint64_t samples = std::uint64_t{width} * height;
    const std::uint64_t fixedBytes = leavesPerSide * leavesPerSide * (1 + (request.roughness ? 80 : 0));
    const std::uint64_t inMemoryBytes =
        (request.sourceHeld ? 0 : samples * 4) + samples * 2 + QuantizedGrid::storageBytes(gridSize) + fixedBytes;
    MemoryPlan plan;
    plan.threads = request.threads;
    plan.inMemory = inMemoryBytes <= budget && !request.forceOutOfCore;
    if (request.pifs && !plan.inMemory) {
        return makeError("--height-codec pifs builds in memory, and a ", width, "x", height, " input needs about ",
                         formatBytes(inMemoryBytes + QuantizedGrid::storageBytes(gridSize) * 4 / 3),
                         (request.forceOutOfCore ? std::string(" (--out-of-core was given)")
                                                 : ", more than the memory budget of " + formatBytes(budget)),
                         ": use the residual codec out of core");
    }
    // Out of core, the samples the nodes above the split read (multiples of the split level's stride) stay
    // in memory beside the scratch file (QuantizedGrid::createMapped).
    plan.coarseShift = std::min(QuantizedGrid::kTileShift, static_cast<int>(header.levels) - 1 - splitLevel(header));
    if (plan.inMemory) {
        return plan;
    }
    const OutOfCoreNeed need(header, fixedBytes, plan.coarseShift, request.gdalCache);
    plan.coreRows = need.coreRowsFor(budget);
    // Each thread holds a subtree's square: as many as fit, saying so when fewer than asked.
    while (plan.threads > 1 && need.bytes(budget, plan.threads) > budget) {
        --plan.threads;
    }
    if (plan.threads < request.threads) {
        warn("building on " + std::to_string(plan.threads) + " thread(s) of the " + std::to_string(request.threads) +
             " asked: each holds a subtree of the grid, and more do not fit the memory budget of " +
             formatBytes(budget));
    }
    if (need.bytes(budget, plan.threads) > budget) {
        // The least budget in whole MiB that covers what it itself needs: the need grows by about a quarter of
        // the budget, so following the need (rounded up to a MiB each time, as the band's rows step with the
        // budget) converges. Following the advice works.
        auto roundUp = [](std::uint64_t bytes) { return (bytes + (std::uint64_t{1} << 20) - 1) >> 20 << 20; };
        std::uint64_t advice = roundUp(need.bytes(budget, plan.threads));
        for (int k = 0; k < 200 && need.bytes(advice, plan.threads) > advice; ++k) {
            advice = roundUp(need.bytes(advice, plan.threads));
        }
        if (!request.forceOutOfCore) {
            advice = std::min(advice, roundUp(inMemoryBytes));  // the whole build in memory may need less
        }
        return makeError("the memory budget of ", formatBytes(budget), " is too small for a ", width, "x", height,
                         " input even out of core on one thread: --memory ", advice >> 20, "M is enough");
    }
    plan.estimatedBytes = need.bytes(budget, plan.threads);
    return plan;
}

std::uint64_t markFilledSquares(std::span<const std::uint8_t> mask, int width, int maskRow0, int core0, int core1,
                                int cells, std::uint64_t leavesPerSide, std::vector<std::uint8_t>& squares)
{
    std::uint64_t filled = 0;
    for (int y = core0; y < core1 && !mask.empty(); ++y) {
        const std::uint8_t* row = mask.data() + static_cast<std::size_t>(y - maskRow0) * width;
        for (int x = 0; x < width; ++x) {
            if (!row[x]) {
                continue;
            }
            ++filled;
            // The finest squares whose closed square holds (x, y): up to four at a corner.
            for (int sy = y / cells - (y % cells == 0 ? 1 : 0); sy <= y / cells; ++sy) {
                for (int sx = x / cells - (x % cells == 0 ? 1 : 0); sx <= x / cells; ++sx) {
                    if (sx >= 0 && sy >= 0 && std::uint64_t(sx) < leavesPerSide && std::uint64_t(sy) < leavesPerSide) {
                        squares[std::uint64_t(sy) * leavesPerSide + std::uint64_t(sx)] = 1;
                    }
                }
            }
        }
    }
    return filled;
}

}  // namespace terrain
