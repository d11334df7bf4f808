// prep's engine (paper 3.2.1-3.2.14, 4.1): a height field in, a .map file out.
#pragma once

#include "core/Expected.h"
#include "heightfield/HeightField.h"
#include "heightfield/HeightRows.h"
#include "quadtree/LeafRoughness.h"
#include "quadtree/MapFormat.h"

#include <array>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace terrain {

/// The sample spacings a map may have (metres): a micrometre to 1000 km.
inline constexpr double kMinSpacingMetres = 1e-6;
inline constexpr double kMaxSpacingMetres = 1e6;

struct BuildOptions {
    int chunkSize = 65;                   ///< N: isValidChunkSize, 2^k + 1 in [3, kMaxChunkSize = 1025]
    std::optional<double> spacing;        ///< -h: metres between samples, used when the file has none
    std::optional<double> verticalScale;  ///< -v: metres per native unit, used when the file has none
    double offset = 0.0;                  ///< --offset: metres added after scaling
    double maxError = 0.0;                ///< --max-error: L-infinity bound in metres, 0 = lossless
    /// --clamp LO,HI: heights (metres, after -v and --offset) below LO become LO, above HI become HI, before
    /// anything else sees them (infinite samples included); LO <= HI.
    std::optional<std::array<double, 2>> clampMetres;
    /// --height-codec: kHeightCodingKobbeltResidual (lossless or within maxError) or kHeightCodingPifs (seed
    /// 003's fractal code: lossy, its error measured and stored; needs maxError 0, chunks >= 9, the build in
    /// memory).
    std::uint32_t heightCoding = kHeightCodingKobbeltResidual;
    int textureSize = 0;  ///< --texture-size: 2^k + 1 up to kMaxTextureSize; 0 = the chunk size
    int threads = 1;
    /// --memory: bytes prep may hold. The input and the code grid are held whole when they fit, otherwise
    /// the input is streamed in bands of rows and the grid lives in a scratch file next to the output (the
    /// same map bytes either way); an error when even that does not fit. 0: half the memory available.
    std::uint64_t memoryBudget = 0;  ///< see effectiveMemoryBudget
    /// --out-of-core: build out of core even when the input fits the budget (tests, benchmarks).
    bool forceOutOfCore = false;
    /// -t: imagery with a CRS (any GDAL RGB(A) raster) aligned by coordinates, the generated colours where it
    /// does not cover; otherwise a PNG stretched over the input.
    std::optional<std::filesystem::path> texture;
    std::optional<std::filesystem::path> weights;  ///< -w: gray weight map for pruning (3.2.13)
    /// libdeflate level. OutOfCoreBench at 16385^2: level 4 builds in 26.9 s to 493.7 MiB, level 6 in
    /// 31.1 s to 484.6 MiB (zlib's level 6 wrote 2% more than libdeflate's level 4 on 8193^2).
    int zlibLevel = 4;
    /// The error of the detail synthesized below static leaf `id` (3.4.1), in metres: finite and >= 0. Gets
    /// the map's header (quantization, spacing, origin) and the leaf's window of W x W height codes (W = N +
    /// 4, rows south to north, metres = heightOffset + heightStep * code). Called once for every leaf, from
    /// the builder's worker threads at once: must be thread-safe, and must depend on its arguments only for
    /// the map not to depend on the thread count. Unset: no detail below the leaves, detailDeltaC = deltaC.
    /// Above the leaves, detailDeltaC = max(children's, the node's measured error + the largest leaf detail
    /// error below it + detailDisplacementRange): the node's data against the leaves', the leaves' against
    /// what is synthesized below them, and the node's own displacement against the leaves' (docs/design.md).
    std::function<float(const MapHeader&, const NodeId&, std::span<const std::uint16_t>)> leafDetailError;
    /// Metres: how far the displacement of a static node can differ from the displacement synthesized below
    /// the leaves (its placement follows its own slopes): 2 x the largest material amplitude. >= 0.
    double detailDisplacementRange = 0.0;
    /// When set, replaces detailDisplacementRange with its value for the map's header (roughness laws
    /// included), for displacements that follow the laws (relative materials). Called once, before the nodes.
    std::function<double(const MapHeader&)> detailDisplacementRangeFor;
    /// What leafDetailError estimates for (the synthesis settings and materials), stored in the map so the
    /// viewer can tell whether its own settings match. Empty: the map says nothing about it.
    std::optional<DetailRecipe> detailRecipe;
    /// Measure each leaf's roughness (measureLeafRoughness) and store it in the map (RoughnessGrid), for the
    /// synthesis to continue below the leaves. Maps of more than 15 levels never get it (with a warning).
    bool measureRoughness = true;
    /// Called now and then with the fraction done (0..1) and the current stage.
    std::function<void(double, std::string_view)> progress;
    /// Called for each warning (an option that had no effect, a default that was assumed).
    std::function<void(std::string_view)> warn;
    /// Called with notes on how the build proceeds (out of core: its bands, threads and estimated memory).
    std::function<void(std::string_view)> note;
};

/// What a build produced, for prep's summary and for benchmarks.
struct BuildReport {
    MapHeader header;
    int inputWidth = 0;
    int inputHeight = 0;
    std::uint64_t nodes = 0;
    std::uint64_t fileBytes = 0;
    std::uint64_t heightBytes = 0;    ///< node height streams
    std::uint64_t textureBytes = 0;   ///< node texture streams
    std::uint64_t storedSamples = 0;  ///< node window samples, borders included
    double seconds = 0.0;
    bool outOfCore = false;          ///< streamed in bands with the grid in a scratch file (BuildOptions::memoryBudget)
    std::uint64_t memoryBudget = 0;  ///< the budget it was built within, bytes
    int threads = 1;                 ///< the worker threads it was built on (fewer than asked where memory is short)
    std::uint64_t estimatedBytes = 0;  ///< out of core: the anonymous memory the plan expected at the peak
    std::uint64_t leaves = 0;
    float maxLeafDetailError = 0.0f;   ///< metres, over the leaves (0 without leafDetailError)
    double meanLeafDetailError = 0.0;  ///< metres
    double leafDetailSeconds = 0.0;    ///< time spent in leafDetailError, summed over the threads
    /// -t with georeferenced imagery: the share of the finest texel lattice it covers fully; empty otherwise.
    std::optional<double> imageryCoverage;
};

/// The budget a build with `options` keeps to: options.memoryBudget, or half the memory available now.
std::uint64_t effectiveMemoryBudget(const BuildOptions& options);

/// Builds the map of the heights `source` gives into `output` (written to a temporary name and renamed),
/// within options.memoryBudget. A source holding its field gives it up (its samples are released once
/// quantized). Errors name the file or option at fault.
Expected<BuildReport> buildMap(HeightRows& source, const BuildOptions& options, const std::filesystem::path& output);
/// The same for a field in memory.
Expected<BuildReport> buildMap(HeightField field, const BuildOptions& options, const std::filesystem::path& output);

}  // namespace terrain
