// The stages of buildMap (QuadtreeBuilder.cpp) that are pure functions of their arguments: the checks of the
// options, the memory plan (in memory or out of core, and on how many threads) and the marking of the finest
// squares that held no-data samples. Declared here so that tests can hold them against a reference.
#pragma once

#include "core/Expected.h"
#include "heightfield/HeightField.h"
#include "heightfield/NoDataFill.h"
#include "quadtree/LeafRoughness.h"
#include "quadtree/MapFormat.h"
#include "quadtree/QuadtreeBuilder.h"

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace terrain {

/// Rows a band of the out-of-core passes reads beyond the rows it produces: the no-data fill's reach, then
/// the roughness lags measured on the filled samples.
inline constexpr int kBandMargin = kFillRings + kRoughnessMargin;

/// The texture size a build with `options` uses: options.textureSize, or the chunk size for 0.
int effectiveTextureSize(const BuildOptions& options);

/// Checks what does not depend on the input's samples, in this order: the chunk size, the texture size, the
/// thread count, the height coding and what fractal coding needs (no --max-error, chunks of at least 9), and
/// that `info` (the input's header) holds at least 2 x 2 samples. The first error found, naming the option.
Status checkBuildOptions(const BuildOptions& options, const HeightField& info);

/// The split level the parallel subtrees start at: deep enough for every core to be busy (64 subtrees) and
/// for a subtree's square to stay within 4096 samples (what the out-of-core build holds per thread). The
/// tree alone decides it, so the file does not depend on the thread count or on the memory budget.
int splitLevel(const MapHeader& header);

/// What the memory plan depends on besides the map's header.
struct MemoryRequest {
    std::uint64_t budget = 0;     ///< bytes the build may hold (effectiveMemoryBudget), > 0
    int threads = 1;              ///< worker threads asked for, >= 1
    bool sourceHeld = false;      ///< the source holds its field: an in-memory build needs no copy of it
    bool roughness = false;       ///< a roughness grid is measured (80 bytes per leaf)
    bool pifs = false;            ///< fractal coding, which builds in memory only
    bool forceOutOfCore = false;  ///< BuildOptions::forceOutOfCore
    bool gdalCache = false;       ///< the source reads through GDAL's block cache (gdalCacheBytesFor the budget)
};

/// How the input and the grid pass through memory (docs/design.md, "Out-of-core prep").
struct MemoryPlan {
    bool inMemory = true;  ///< the input and the code grid held whole
    int coreRows = 0;      ///< out of core: rows a band produces, a multiple of the chunk's cells; 0 in memory
    int threads = 1;       ///< worker threads: those asked for, fewer out of core where the budget holds no more
    int coarseShift = 0;   ///< out of core: the coarse lattice's shift kept in memory (QuantizedGrid::createMapped)
    std::uint64_t estimatedBytes = 0;  ///< out of core: the anonymous memory expected at the peak, bytes
};

/// Plans a build of the map `header` describes (chunkSize, levels, validWidth x validHeight: the input's
/// size): in memory when the input (unless held), its 2-byte codes, the grid and 1 byte (+80 with roughness)
/// per leaf fit request.budget and out of core is not forced; otherwise bands of a quarter of the budget (at
/// 6 bytes a sample), on as many of the threads asked for as the estimated peak allows: the process's base,
/// the reader's cache, the per-map structures, what the allocator keeps of a band, and the larger of the band
/// (9 bytes a sample while read) and 2.5 bytes a sample of each thread's subtree (BuildStages.cpp gives how each
/// term was measured). Errors: fractal coding that
/// does not fit in memory, and a budget too small even out of core on one thread (naming the least --memory
/// that is enough, in MiB). `warn` is told when the plan builds on fewer threads than asked.
Expected<MemoryPlan> planMemory(const MapHeader& header, const MemoryRequest& request,
                                const std::function<void(const std::string&)>& warn);

/// Marks the finest-level squares (leavesPerSide^2, row-major in `squares`, each `cells` samples wide with
/// its closed edges) that hold a sample flagged in `mask` among rows [core0, core1); `mask` holds `width`
/// bytes per row from row `maskRow0` on. Returns the flagged samples counted.
std::uint64_t markFilledSquares(std::span<const std::uint8_t> mask, int width, int maskRow0, int core0, int core1,
                                int cells, std::uint64_t leavesPerSide, std::vector<std::uint8_t>& squares);

}  // namespace terrain
