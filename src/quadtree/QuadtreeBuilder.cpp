// The preprocessor (paper 4.1.1): quantize, reconstruct, simplify (3.2.3), measure errors (3.2.5, eq. 3.1)
// and bounds (3.2.12), prune (3.2.13), texture (3.2.7), code and write (3.2.14).
#include "quadtree/QuadtreeBuilder.h"

#include "core/AtomicFile.h"
#include "core/Check.h"
#include "core/Memory.h"
#include "core/ParallelFor.h"
#include "heightfield/GdalRaster.h"
#include "heightfield/NoDataFill.h"
#include "quadtree/BuildStages.h"
#include "quadtree/HeightCodec.h"
#include "quadtree/NodeTexture.h"
#include "quadtree/PifsCodec.h"
#include "quadtree/QuantizedGrid.h"
#include "quadtree/SimplificationError.h"
#include "quadtree/TextureCodec.h"
#include "quadtree/WeightMap.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

namespace terrain {

namespace {

/// Which static nodes exist: a node at level k < levels-1 has children unless it lies wholly in the padding
/// or the weight map asks for no more depth there.
class TreeShape {
public:
    TreeShape(const MapHeader& header, const WeightMap* weights) : mFlags(header.levels)
    {
        const double validX1 = header.validX0 + header.validWidth - 1.0;
        const double validY1 = header.validY0 + header.validHeight - 1.0;
        for (std::uint32_t level = 0; level < header.levels; ++level) {
            const std::uint32_t side = 1u << level;
            mFlags[level].assign(std::size_t{side} * side, 0);
        }
        mFlags[0][0] = kExists;
        for (std::uint32_t level = 0; level + 1 < header.levels; ++level) {
            const std::uint32_t side = 1u << level;
            const double size = (header.chunkSize - 1) * std::ldexp(1.0, static_cast<int>(header.levels - 1 - level));
            for (std::uint32_t y = 0; y < side; ++y) {
                for (std::uint32_t x = 0; x < side; ++x) {
                    NodeId id{static_cast<int>(level), x, y};
                    if (!exists(id)) {
                        continue;
                    }
                    // Padding only: the node's open square misses the valid region.
                    bool padding = !(x * size < validX1 && (x + 1) * size > header.validX0 && y * size < validY1 &&
                                     (y + 1) * size > header.validY0);
                    // A one-sample-wide input still needs its line of samples: keep nodes touching it.
                    if (header.validWidth == 1 || header.validHeight == 1) {
                        padding = !(x * size <= validX1 && (x + 1) * size >= header.validX0 && y * size <= validY1 &&
                                    (y + 1) * size >= header.validY0);
                    }
                    bool wanted = !weights || weights->deepestLevelWanted(id) > static_cast<int>(level);
                    if (!padding && wanted) {
                        flags(id) |= kHasChildren;
                        for (int q = 0; q < 4; ++q) {
                            flags(id.child(q)) |= kExists;
                        }
                    }
                }
            }
        }
    }

    bool exists(const NodeId& id) const { return (flags(id) & kExists) != 0; }
    bool hasChildren(const NodeId& id) const { return (flags(id) & kHasChildren) != 0; }
    std::uint64_t count() const
    {
        std::uint64_t n = 0;
        for (const auto& level : mFlags) {
            n += static_cast<std::uint64_t>(
                std::count_if(level.begin(), level.end(), [](auto f) { return f & kExists; }));
        }
        return n;
    }
    std::vector<NodeId> nodesAt(int level) const
    {
        std::vector<NodeId> ids;
        const std::uint32_t side = 1u << level;
        for (std::uint32_t i = 0; i < mFlags[level].size(); ++i) {
            if (mFlags[level][i] & kExists) {
                ids.push_back({level, i % side, i / side});
            }
        }
        return ids;
    }

private:
    static constexpr std::uint8_t kExists = 1;
    static constexpr std::uint8_t kHasChildren = 2;
    std::uint8_t& flags(const NodeId& id) { return mFlags[id.level][(std::size_t{id.y} << id.level) + id.x]; }
    std::uint8_t flags(const NodeId& id) const { return mFlags[id.level][(std::size_t{id.y} << id.level) + id.x]; }
    std::vector<std::vector<std::uint8_t>> mFlags;
};

/// What a processed node hands its parent.
struct NodeSummary {
    bool hasFilledNoData = false;  ///< the node's square holds input samples that were no-data
    float deltaM = 0.0f;
    float deltaC = 0.0f;
    float detailDeltaC = 0.0f;         ///< the error with the detail synthesized below the leaves (3.4.1)
    float leafDetail = 0.0f;           ///< the largest leaf detail error in the subtree
    std::uint32_t leafCodecError = 0;  ///< fractal coding: the largest stored-vs-input error of its leaves, codes
    std::uint16_t minCode = 0;
    std::uint16_t maxCode = 0;
    std::vector<std::uint8_t> texture;
};

/// Encoded nodes in file order, with offsets relative to the start of `bytes`.
struct EncodedBlock {
    std::vector<DirectoryEntry> entries;
    std::vector<std::uint8_t> bytes;
    std::uint64_t storedSamples = 0;
    std::uint64_t heightBytes = 0;
    std::uint64_t textureBytes = 0;
};

/// The measured errors (directErrorCodesWithin) of the nodes above the split level, gathered per subtree
/// at the split level while its region of the grid is at hand: codes[i][level] for subtree i and its
/// ancestor at `level`.
struct SplitPartials {
    int split = 0;
    std::vector<NodeId> subtrees;
    std::vector<std::vector<double>> codes;

    const std::vector<double>* of(const NodeId& id) const
    {
        auto it = std::find(subtrees.begin(), subtrees.end(), id);
        return it == subtrees.end() ? nullptr : &codes[static_cast<std::size_t>(it - subtrees.begin())];
    }
};

class Builder {
public:
    Builder(const MapHeader& header, const QuantizedGrid& grid, const TreeShape& shape, const TextureSource& texture,
            const std::vector<std::uint8_t>& filledSquares, const SplitPartials& partials, const BuildOptions& options,
            const PifsPyramid* pifs, std::atomic<std::uint64_t>& done, std::atomic<std::int64_t>& detailNanoseconds)
        : mHeader(header),
          mGrid(grid),
          mPifs(pifs),
          mShape(shape),
          mTexture(texture),
          mFilledSquares(filledSquares),
          mPartials(partials),
          mOptions(options),
          mWindow(header),
          mDone(done),
          mDetailNanoseconds(detailNanoseconds)
    {
    }

    /// Processes `id`'s subtree depth first, appending every sibling group below `id` to `out` (children
    /// groups before their parents: post order). `known` supplies summaries of nodes already processed
    /// (subtree roots done by other workers); `id` itself is emitted by its parent.
    NodeSummary process(const NodeId& id, EncodedBlock& out,
                        const std::function<const NodeSummary*(const NodeId&)>& known) const
    {
        if (const NodeSummary* summary = known(id)) {
            return *summary;
        }
        std::vector<std::uint16_t> window(mWindow.sampleCount());
        storedWindow(id, window);
        const WindowRect inside = mWindow.insideRect(id);
        NodeSummary summary;
        summary.minCode = 65535;
        for (int y = inside.y0; y <= inside.y1; ++y) {
            for (int x = inside.x0; x <= inside.x1; ++x) {
                auto code = window[static_cast<std::size_t>(y) * mWindow.size() + x];
                summary.minCode = std::min(summary.minCode, code);
                summary.maxCode = std::max(summary.maxCode, code);
            }
        }
        if (!mShape.hasChildren(id)) {
            // A leaf of the stored tree: its texture comes from the same pyramid as its neighbours', even
            // when it was pruned above the finest level, so edges shared with them match exactly.
            summary.texture = texturePyramid(id);
            summary.hasFilledNoData = containsFilledSample(id);
            summary.detailDeltaC = leafDetailError(id, window);
            summary.leafDetail = summary.detailDeltaC;
            summary.leafCodecError = mPifs ? mPifs->errorCodes(id) : 0;
            ++mDone;
            return summary;
        }
        std::array<NodeSummary, 4> children;
        for (int q = 0; q < 4; ++q) {
            children[q] = process(id.child(q), out, known);
        }
        // Emit the four children together (3.2.14: siblings are loaded together).
        float worstChild = 0.0f;
        float worstChildDetail = 0.0f;
        for (int q = 0; q < 4; ++q) {
            const NodeId child = id.child(q);
            emit(child, heightStream(child, window), children[q], out);
            worstChild = std::max(worstChild, children[q].deltaC);
            worstChildDetail = std::max(worstChildDetail, children[q].detailDeltaC);
            summary.leafDetail = std::max(summary.leafDetail, children[q].leafDetail);
            summary.leafCodecError = std::max(summary.leafCodecError, children[q].leafCodecError);
            summary.hasFilledNoData = summary.hasFilledNoData || children[q].hasFilledNoData;
            summary.minCode = std::min(summary.minCode, children[q].minCode);
            summary.maxCode = std::max(summary.maxCode, children[q].maxCode);
        }
        summary.deltaM = static_cast<float>(simplificationError(id) * mHeader.heightStep);
        // The measured distance to the finest data, nested with max and a margin for the geomorph
        // (kErrorNesting; eq. 3.1 summed delta_m over the levels, an upper bound of this that grows
        // with every level). Fractal coding stores neither the node nor the leaves as the input has them: the
        // distance between what they store is at most the input's plus both their coding errors.
        const double codecError = mPifs ? static_cast<double>(mPifs->errorCodes(id)) + summary.leafCodecError : 0.0;
        const float direct = static_cast<float>((directError(id) + codecError) * mHeader.heightStep);
        summary.deltaC = std::max(kErrorNesting * worstChild, direct);
        summary.detailDeltaC =
            mOptions.leafDetailError
                ? std::max(kErrorNesting * worstChildDetail,
                           direct + summary.leafDetail + static_cast<float>(mOptions.detailDisplacementRange))
                : summary.deltaC;
        summary.texture.resize(std::size_t{mHeader.textureSize} * mHeader.textureSize * 3);
        downsampleChildTextures({children[0].texture, children[1].texture, children[2].texture, children[3].texture},
                                static_cast<int>(mHeader.textureSize), summary.texture);
        ++mDone;
        if (id.level < mPartials.split) {
            mGrid.releaseAll();  // a node above the split touched its square at its children's stride
        }
        return summary;
    }

    /// The measured errors of `subtree`'s ancestors within it (SplitPartials), indexed by their level.
    std::vector<double> partialsOf(const NodeId& subtree) const
    {
        std::vector<double> codes(static_cast<std::size_t>(subtree.level));
        NodeId ancestor = subtree;
        for (int level = subtree.level - 1; level >= 0; --level) {
            ancestor = ancestor.parent();
            codes[static_cast<std::size_t>(level)] = directErrorCodesWithin(
                mGrid, mHeader, ancestor, subtree, [this](const NodeId& n) { return mShape.hasChildren(n); });
        }
        return codes;
    }

    /// Emits the root, which has no parent to be emitted by.
    void emitRoot(const NodeSummary& root, EncodedBlock& out) const
    {
        emit(NodeId::root(), heightStream(NodeId::root(), {}), root, out);
    }

private:
    /// The heights node `id` stores: the (reconstructed) grid's, or the fractal pyramid's.
    void storedWindow(const NodeId& id, std::span<std::uint16_t> window) const
    {
        if (mPifs) {
            mPifs->extractWindow(id, window);
        } else {
            mGrid.extractWindow(mHeader, id, window);
        }
    }

    /// Node `id`'s height stream; `parent` is its parent's stored window (empty for the root).
    std::vector<std::uint8_t> heightStream(const NodeId& id, std::span<const std::uint16_t> parent) const
    {
        if (mPifs) {
            return mPifs->stream(id);
        }
        std::vector<std::uint16_t> window(mWindow.sampleCount());
        mGrid.extractWindow(mHeader, id, window);
        return encodeNodeHeights(mWindow, id, window, parent, mHeader.quantizerBin, mOptions.zlibLevel);
    }

    /// delta_m in codes, from what the children store (MapVerifier measures the same from the decoded map).
    double simplificationError(const NodeId& id) const
    {
        if (!mPifs) {
            return simplificationErrorCodes(mGrid, mHeader, id);
        }
        const std::uint64_t x0 = std::uint64_t{id.x} * 2 * (mHeader.chunkSize - 1);
        const std::uint64_t y0 = std::uint64_t{id.y} * 2 * (mHeader.chunkSize - 1);
        return simplificationErrorCodes(static_cast<int>(mHeader.chunkSize), [&](int a, int b) -> std::int32_t {
            return mPifs->at(id.level + 1, x0 + static_cast<std::uint64_t>(a), y0 + static_cast<std::uint64_t>(b));
        });
    }

    /// The estimated error of the detail synthesized below leaf `id` (3.4.1); 0 without an estimator.
    float leafDetailError(const NodeId& id, std::span<const std::uint16_t> window) const
    {
        if (!mOptions.leafDetailError) {
            return 0.0f;
        }
        const auto start = std::chrono::steady_clock::now();
        const float error = mOptions.leafDetailError(mHeader, id, window);
        TERRAIN_EXPECTS(std::isfinite(error) && error >= 0.0f, "leafDetailError must return a finite error >= 0");
        const auto spent = std::chrono::steady_clock::now() - start;
        mDetailNanoseconds += std::chrono::duration_cast<std::chrono::nanoseconds>(spent).count();
        return error;
    }

    /// The texture of `id` as the pyramid from the finest level makes it.
    std::vector<std::uint8_t> texturePyramid(const NodeId& id) const
    {
        std::vector<std::uint8_t> texture(std::size_t{mHeader.textureSize} * mHeader.textureSize * 3);
        if (id.level + 1 == static_cast<int>(mHeader.levels)) {
            sampleNodeTexture(mTexture, mHeader, id, texture);
            return texture;
        }
        std::array<std::vector<std::uint8_t>, 4> children;
        for (int q = 0; q < 4; ++q) {
            children[q] = texturePyramid(id.child(q));
        }
        downsampleChildTextures({children[0], children[1], children[2], children[3]},
                                static_cast<int>(mHeader.textureSize), texture);
        return texture;
    }

    /// Whether the node's square (edges included) holds an input sample that was no-data: whether one of
    /// the finest-level squares it is made of does.
    bool containsFilledSample(const NodeId& id) const
    {
        const int shift = static_cast<int>(mHeader.levels) - 1 - id.level;
        const std::uint64_t side = std::uint64_t{1} << (mHeader.levels - 1);
        for (std::uint64_t y = std::uint64_t{id.y} << shift; y < (std::uint64_t{id.y} + 1) << shift; ++y) {
            for (std::uint64_t x = std::uint64_t{id.x} << shift; x < (std::uint64_t{id.x} + 1) << shift; ++x) {
                if (mFilledSquares[y * side + x]) {
                    return true;
                }
            }
        }
        return false;
    }

    /// The measured error of `id` in codes: directly below the split, from the subtrees' partials above it
    /// (and any leaf above the split directly).
    double directError(const NodeId& id) const
    {
        auto hasChildren = [this](const NodeId& n) { return mShape.hasChildren(n); };
        if (id.level >= mPartials.split) {
            return directErrorCodes(mGrid, mHeader, id, hasChildren);
        }
        double worst = 0.0;
        std::vector<NodeId> stack{id};
        while (!stack.empty()) {
            const NodeId at = stack.back();
            stack.pop_back();
            if (at.level == mPartials.split) {
                const std::vector<double>* partial = mPartials.of(at);
                TERRAIN_EXPECTS(partial != nullptr, "every subtree at the split has its partials");
                worst = std::max(worst, (*partial)[static_cast<std::size_t>(id.level)]);
            } else if (hasChildren(at)) {
                for (int q = 0; q < 4; ++q) {
                    stack.push_back(at.child(q));
                }
            } else {
                worst = std::max(worst, directErrorCodesWithin(mGrid, mHeader, id, at, hasChildren));
            }
        }
        return worst;
    }

    void emit(const NodeId& id, std::vector<std::uint8_t> heights, const NodeSummary& summary, EncodedBlock& out) const
    {
        auto texture = encodeTexture(summary.texture, static_cast<int>(mHeader.textureSize), mOptions.zlibLevel);
        DirectoryEntry entry;
        entry.id = id;
        entry.hasChildren = mShape.hasChildren(id);
        entry.hasFilledNoData = summary.hasFilledNoData;
        entry.offset = out.bytes.size();
        entry.heightBytes = static_cast<std::uint32_t>(heights.size());
        entry.textureBytes = static_cast<std::uint32_t>(texture.size());
        entry.deltaM = summary.deltaM;
        entry.deltaC = summary.deltaC;
        entry.detailDeltaC = summary.detailDeltaC;
        entry.minCode = summary.minCode;
        entry.maxCode = summary.maxCode;
        out.bytes.insert(out.bytes.end(), heights.begin(), heights.end());
        out.bytes.insert(out.bytes.end(), texture.begin(), texture.end());
        entry.crc = crc32Of(std::span(out.bytes).subspan(entry.offset));
        out.entries.push_back(entry);
        out.heightBytes += heights.size();
        out.textureBytes += texture.size();
        out.storedSamples += mWindow.sampleCount();
    }

    const MapHeader& mHeader;
    const QuantizedGrid& mGrid;
    const PifsPyramid* mPifs;  ///< fractal coding's stored heights and streams; null for the residual coding
    const TreeShape& mShape;
    const TextureSource& mTexture;
    const std::vector<std::uint8_t>& mFilledSquares;  ///< per finest-level node: its square held a no-data sample
    const SplitPartials& mPartials;
    const BuildOptions& mOptions;
    NodeWindow mWindow;
    std::atomic<std::uint64_t>& mDone;
    std::atomic<std::int64_t>& mDetailNanoseconds;  ///< time spent in options.leafDetailError, all threads
};

}  // namespace

namespace {

using Warn = std::function<void(const std::string&)>;

/// How the input passes through memory: whole (one band, the field held) or in bands of whole leaf rows.
struct InputPlan {
    bool inMemory = true;
    int coreRows = 0;  ///< rows a band produces (a multiple of the leaf rows), out of core
    std::optional<std::array<float, 2>> clampNative;  ///< BuildOptions::clampMetres in native units
};

/// The samples within plan.clampNative, where it is given (NaN stays NaN).
void clampSamples(std::span<float> samples, const InputPlan& plan)
{
    if (plan.clampNative) {
        const auto [lo, hi] = *plan.clampNative;
        for (float& v : samples) {
            v = v < lo ? lo : v > hi ? hi : v;
        }
    }
}

/// The input as the passes over its rows see it: the field held whole, or bands of rows read from the source.
struct InputRows {
    HeightRows& source;
    HeightField* field = nullptr;  ///< the whole input in memory; null out of core
    InputPlan plan;

    /// Calls fn(window, windowRow0, windowRows, core0, core1) for bands whose cores [core0, core1) cover the
    /// field's rows in order, each window holding its core and `margin` rows beyond it on each side (as far
    /// as the field goes): the held field at once, or bands read from the source (clamped).
    Status forEachBand(int margin, const std::function<Status(std::span<float>, int, int, int, int)>& fn) const
    {
        const int width = source.info().width, height = source.info().height;
        if (field) {
            return fn(field->samples, 0, height, 0, height);
        }
        std::vector<float> buffer;
        for (int core0 = 0; core0 < height; core0 += plan.coreRows) {
            const int core1 = std::min(height, core0 + plan.coreRows);
            const int w0 = std::max(0, core0 - margin), w1 = std::min(height, core1 + margin);
            buffer.resize(static_cast<std::size_t>(w1 - w0) * width);
            TERRAIN_TRY(source.readRows(w0, w1 - w0, buffer));
            clampSamples(buffer, plan);
            TERRAIN_TRY(fn(buffer, w0, w1 - w0, core0, core1));
        }
        return {};
    }
};

/// Metres between samples and metres per native unit.
struct SampleUnits {
    double spacing = 1.0;
    double scale = 1.0;
};

/// Spacing and vertical scale: the file's own win (paper 4.4.1), the options fill in what it lacks (else a
/// spacing of 1 m, with a warning, and a scale of 1); an option the file overrides is warned about. Errors: a
/// spacing outside [kMinSpacingMetres, kMaxSpacingMetres] and a non-finite --offset. The scale is checked
/// once the samples are read (measureInput), as it always was.
Expected<SampleUnits> resolveUnits(const HeightField& info, const BuildOptions& options, const Warn& warn)
{
    SampleUnits units;
    if (info.spacing) {
        units.spacing = *info.spacing;
        if (options.spacing && *options.spacing != units.spacing) {
            warn("-h " + std::to_string(*options.spacing) + " has no effect: the file gives a spacing of " +
                 std::to_string(units.spacing) + " m");
        }
    } else if (options.spacing) {
        units.spacing = *options.spacing;
    } else {
        warn("the file gives no sample spacing and -h was not given: using 1 m");
    }
    if (!(units.spacing >= kMinSpacingMetres && units.spacing <= kMaxSpacingMetres)) {
        return makeError("sample spacing ", units.spacing, " m", info.spacing ? " (the file's)" : "", " must be in [",
                         kMinSpacingMetres, ", ", kMaxSpacingMetres, "] m");
    }
    if (info.verticalScale) {
        units.scale = *info.verticalScale;
        if (options.verticalScale && *options.verticalScale != units.scale) {
            warn("-v " + std::to_string(*options.verticalScale) +
                 " has no effect: the file gives a vertical scale of " + std::to_string(units.scale));
        }
    } else if (options.verticalScale) {
        units.scale = *options.verticalScale;
    }
    if (!std::isfinite(options.offset)) {
        return makeError("offset ", options.offset, " must be a finite number");
    }
    return units;
}

/// The map's header as the input's size and the options decide it before a sample is read: chunk and texture
/// sizes, the levels whose grid covers the input (at most 24), spacing, origin, valid region, source,
/// georeference and detail recipe.
Expected<MapHeader> headerFor(const HeightField& info, const BuildOptions& options, double spacing)
{
    const int width = info.width, height = info.height;
    MapHeader header;
    header.chunkSize = static_cast<std::uint32_t>(options.chunkSize);
    header.textureSize = static_cast<std::uint32_t>(effectiveTextureSize(options));
    header.levels = 1;
    while (header.gridSize() < static_cast<std::uint64_t>(std::max(width, height))) {
        ++header.levels;
    }
    if (header.levels > 24) {
        return makeError("height field of ", width, "x", height, " needs more than 24 levels");
    }
    header.sampleSpacing = spacing;
    header.originX = info.originX;
    header.originY = info.originY;
    header.validWidth = static_cast<std::uint32_t>(width);
    header.validHeight = static_cast<std::uint32_t>(height);
    header.source = info.description;
    setGeoreference(header, info.crsWkt, info.crsUnitMetres);
    setDetailRecipe(header, options.detailRecipe);
    return header;
}

/// Whether the map gets a roughness grid: when asked for and the map has at most 15 levels (a warning when
/// asked for and it has more).
bool measuresRoughness(const MapHeader& header, const BuildOptions& options, const Warn& warn)
{
    const bool roughness = options.measureRoughness && header.levels <= 15;
    if (options.measureRoughness && !roughness) {
        warn("a map of " + std::to_string(header.levels) +
             " levels is too large for a roughness grid: the detail below its leaves will not continue the "
             "terrain's roughness");
    }
    return roughness;
}

/// The input whole, for an in-memory build: the source's own field when it holds one (given up), else read.
Status holdInput(HeightRows& source, HeightField& whole)
{
    if (HeightField* held = source.held()) {
        whole = std::move(*held);
        return {};
    }
    const HeightField& info = source.info();
    const std::uint64_t samples =
        std::uint64_t{static_cast<std::uint32_t>(info.width)} * static_cast<std::uint32_t>(info.height);
    TERRAIN_TRY(checkAllocation(
        samples * 4, "a " + std::to_string(info.width) + "x" + std::to_string(info.height) + " height field"));
    const int height = info.height;
    whole = info;
    whole.samples.resize(samples);
    return source.readRows(0, height, whole.samples);
}

/// BuildOptions::clampMetres in native units (metres = base + scale x native, the ends clamped to float's
/// range); empty without it. Error: LO > HI or either beyond kMaxHeightMetres.
Expected<std::optional<std::array<float, 2>>> clampInNativeUnits(const BuildOptions& options, double base, double scale)
{
    if (!options.clampMetres) {
        return std::optional<std::array<float, 2>>{};
    }
    const auto [lo, hi] = *options.clampMetres;
    if (!(lo <= hi && std::abs(lo) <= kMaxHeightMetres && std::abs(hi) <= kMaxHeightMetres)) {
        return makeError("--clamp ", lo, ",", hi, ": LO <= HI, both within +-", kMaxHeightMetres, " m");
    }
    auto native = [&](double metres) {
        constexpr double kMax = std::numeric_limits<float>::max();
        return static_cast<float>(std::clamp((metres - base) / scale, -kMax, kMax));
    };
    return std::optional(std::array<float, 2>{native(lo), native(hi)});
}

/// What pass 1 learns of the input.
struct InputStatistics {
    SampleStatistics statistics;  ///< of the valid samples
    FarFillGrid far;              ///< the far fill's block means; empty when every sample is valid
};

/// Pass 1: the valid samples' statistics and the far fill's block means. Errors: no valid sample, a vertical
/// scale that is not positive and finite, heights out of range (checkSampleRange, metres = baseOffset +
/// scale x native).
Expected<InputStatistics> measureInput(const InputRows& input, double scale, double baseOffset)
{
    const int width = input.source.info().width, height = input.source.info().height;
    SampleStatistics statistics(width, height);
    FarFillBuilder farBuilder(width, height);
    TERRAIN_TRY(input.forEachBand(0, [&](std::span<float> rows, int, int, int core0, int core1) -> Status {
        statistics.addRows(core0, core1 - core0, rows);
        farBuilder.addRows(core0, core1 - core0, rows);
        return {};
    }));
    if (statistics.valid() == 0) {
        return makeError("height field has no valid sample (every sample is no-data)");
    }
    if (!(scale > 0) || !std::isfinite(scale)) {
        return makeError("vertical scale ", scale, " must be a positive finite number");
    }
    TERRAIN_TRY(checkSampleRange(statistics, scale, baseOffset));
    const std::uint64_t samples = std::uint64_t{static_cast<std::uint32_t>(width)} * static_cast<std::uint32_t>(height);
    FarFillGrid far = statistics.valid() < samples ? farBuilder.finish() : FarFillGrid{};
    return InputStatistics{std::move(statistics), std::move(far)};
}

/// The quantization (chooseQuantization), passing over the rows again (pass 1b) where float samples may lie
/// on a lattice, written into `header`; warns when --max-error leaves the heights lossless.
Expected<Quantization> chooseMapQuantization(const InputRows& input, const SampleStatistics& statistics, double scale,
                                             double baseOffset, const BuildOptions& options, MapHeader& header,
                                             const Warn& warn)
{
    const int width = input.source.info().width;
    auto quantization = chooseQuantization(
        statistics, input.source.info().integerSamples, scale, baseOffset, options.maxError,
        [&](double g) -> Expected<std::optional<double>> {
            // Pass 1b, for float input that may lie on a lattice: every valid sample's distance from it.
            std::optional<double> worst = 0.0;
            TERRAIN_TRY(input.forEachBand(0, [&](std::span<float> rows, int, int, int core0, int core1) {
                if (worst) {
                    auto band = latticeDeviation(rows.first(static_cast<std::size_t>(core1 - core0) * width),
                                                 statistics.lo(), statistics.hi(), g);
                    worst = band ? std::optional(std::max(*worst, *band)) : std::nullopt;
                }
                return Status{};
            }));
            return worst;
        });
    TERRAIN_TRY(quantization);
    header.heightOffset = quantization->offset;
    header.heightStep = quantization->step;
    header.quantizerBin = quantization->bin;
    header.maxErrorBound = quantization->errorBound;
    if (options.maxError > 0 && quantization->bin == 1 && quantization->errorBound == 0) {
        char message[200];
        std::snprintf(message, sizeof message,
                      options.maxError < quantization->step
                          ? "--max-error %g m is below one height step (%g m): storing losslessly"
                          : "--max-error %g m: the heights fill the 16-bit codes at a step of %g m, leaving no "
                            "room for lossy codes: storing losslessly",
                      options.maxError, quantization->step);
        warn(message);
    }
    return quantization;
}

/// Codes of rows [core0, core1) of a band whose rows start at row w0, on `threads` threads; the padding
/// columns repeat each row's last code.
void quantizeRows(QuantizedGrid& grid, std::span<const float> rows, int width, int w0, int core0, int core1,
                  const Quantization& quantization, int threads)
{
    parallelFor(static_cast<std::size_t>(core1 - core0), threads, [&](std::size_t k) {
        const int y = core0 + static_cast<int>(k);
        const float* row = rows.data() + static_cast<std::size_t>(y - w0) * width;
        for (int x = 0; x < width; ++x) {
            grid.at(static_cast<std::uint64_t>(x), static_cast<std::uint64_t>(y)) =
                quantizeNative(row[x], quantization);
        }
        const std::uint16_t last = grid.at(static_cast<std::uint64_t>(width - 1), static_cast<std::uint64_t>(y));
        for (std::uint32_t x = static_cast<std::uint32_t>(width); x < grid.size(); ++x) {
            grid.at(x, static_cast<std::uint64_t>(y)) = last;
        }
    });
}

/// The padding rows below the input's `height` rows, each a copy of its last row, released as written.
void padLastRow(QuantizedGrid& grid, int height)
{
    const std::uint32_t gridSize = grid.size();
    for (std::uint32_t y = static_cast<std::uint32_t>(height); y < gridSize; ++y) {
        for (std::uint32_t x = 0; x < gridSize; ++x) {
            grid.at(x, y) = grid.at(x, static_cast<std::uint64_t>(height - 1));
        }
        if (y % 256 == 255) {
            grid.release(0, (y - 255) & ~std::uint32_t{63}, gridSize, y + 1);
        }
    }
}

/// What pass 2 leaves.
struct QuantizedInput {
    QuantizedGrid grid;                         ///< the codes, the padding repeating the last column and row
    std::vector<std::uint8_t> filledSquares;    ///< per finest-level square: it held a no-data sample
    std::uint64_t filled = 0;                   ///< no-data samples filled
    std::uint16_t lowest = 65535, highest = 0;  ///< over the input's codes
    std::optional<RoughnessGrid> roughness;     ///< the leaves' roughness, where measured
};

/// Pass 2: fills the no-data samples, measures the leaves' roughness (when `roughness`), quantizes into the
/// grid (in memory, or a scratch file in `scratchDirectory` out of core) and marks the squares that held
/// no-data samples.
Expected<QuantizedInput> quantizeInput(const InputRows& input, const MapHeader& header,
                                       const InputStatistics& statistics, const Quantization& quantization,
                                       double scale, bool roughness, int threads,
                                       const std::filesystem::path& scratchDirectory, int coarseShift)
{
    const int width = input.source.info().width, height = input.source.info().height;
    const std::uint64_t samples = std::uint64_t{static_cast<std::uint32_t>(width)} * static_cast<std::uint32_t>(height);
    const auto gridSize = static_cast<std::uint32_t>(header.gridSize());
    const int cells = static_cast<int>(header.chunkSize) - 1;
    const std::uint64_t leavesPerSide = std::uint64_t{1} << (header.levels - 1);
    auto grid = input.plan.inMemory ? QuantizedGrid::create(gridSize)
                                    : QuantizedGrid::createMapped(gridSize, scratchDirectory, coarseShift);
    TERRAIN_TRY(grid);
    QuantizedInput out{std::move(grid.value()),
                       std::vector<std::uint8_t>(leavesPerSide * leavesPerSide, 0),
                       0,
                       65535,
                       0,
                       std::nullopt};
    std::optional<LeafRoughnessMeter> meter;
    if (roughness) {
        meter.emplace(width, height, scale, header);
    }
    std::vector<std::uint8_t> mask;
    TERRAIN_TRY(input.forEachBand(kBandMargin, [&](std::span<float> rows, int w0, int wrows, int core0, int core1) {
        if (statistics.statistics.valid() < samples) {
            fillNoDataRows(rows, width, wrows, w0, statistics.far, &mask);
        }
        out.filled += markFilledSquares(mask, width, w0, core0, core1, cells, leavesPerSide, out.filledSquares);
        if (meter) {
            const int ly0 = core0 / cells;
            const int ly1 = core1 == height ? meter->leafRows() : core1 / cells;
            meter->addLeafRows(ly0, ly1, rows, w0, wrows, threads);
        }
        quantizeRows(out.grid, rows, width, w0, core0, core1, quantization, threads);
        for (int y = core0; y < core1; ++y) {
            for (int x = 0; x < width; ++x) {
                const std::uint16_t code = out.grid.at(static_cast<std::uint64_t>(x), static_cast<std::uint64_t>(y));
                out.lowest = std::min(out.lowest, code);
                out.highest = std::max(out.highest, code);
            }
        }
        out.grid.release(0, static_cast<std::uint64_t>(core0) & ~std::uint64_t{63}, gridSize,
                         static_cast<std::uint64_t>(core1));
        return Status{};
    }));
    padLastRow(out.grid, height);
    out.grid.releaseAll();
    if (meter) {
        out.roughness = meter->finish();
    }
    return out;
}

/// The finest level's texel lattice over the valid region, in the map's CRS.
RasterGrid textureLattice(const MapHeader& header)
{
    const double texelsPerSample = (header.textureSize - 1.0) / (header.chunkSize - 1.0);
    RasterGrid lattice;
    lattice.width = static_cast<int>(std::ceil((header.validWidth - 1.0) * texelsPerSample - 1e-9)) + 1;
    lattice.height = static_cast<int>(std::ceil((header.validHeight - 1.0) * texelsPerSample - 1e-9)) + 1;
    lattice.step = header.sampleSpacing / texelsPerSample;
    lattice.x0 = header.originX + header.validX0 * header.sampleSpacing;
    lattice.y0 = header.originY + header.validY0 * header.sampleSpacing;
    lattice.crsWkt = header.crsWkt;
    lattice.crsUnitMetres = header.crsUnitMetres;
    return lattice;
}

/// What the nodes' textures are sampled from, and what that refers to.
struct MapTexture {
    std::unique_ptr<TextureSource> generated;  ///< colours from the heights (imagery's fallback); null when `source`
    std::unique_ptr<Image> image;              ///< a stretched PNG's pixels, which `source` refers to
    std::unique_ptr<TextureSource> source;
    std::optional<double> imageryCoverage;  ///< georeferenced imagery: the share of the lattice it covers
};

/// The texture (-t): georeferenced imagery aligned by coordinates over the colours generated from the heights
/// (between codes lowest and highest), a PNG stretched over the input, or those colours alone. Out of core,
/// imagery whose texel lattice takes more than half of `budget` is an error. `header` and `grid` must outlive
/// the result.
Expected<MapTexture> chooseTexture(const BuildOptions& options, const MapHeader& header, const QuantizedGrid& grid,
                                   std::uint16_t lowest, std::uint16_t highest, bool inMemory, std::uint64_t budget)
{
    MapTexture texture;
    texture.generated =
        std::make_unique<HeightColouring>(grid, header, header.heightOf(lowest), header.heightOf(highest));
    if (options.texture && isGeoreferencedRaster(*options.texture)) {
        const RasterGrid lattice = textureLattice(header);
        const std::uint64_t latticeBytes =
            std::uint64_t{static_cast<std::uint32_t>(lattice.width)} * static_cast<std::uint32_t>(lattice.height) * 4;
        if (!inMemory && latticeBytes > budget / 2) {
            return makeError(options.texture->string(), ": imagery resampled onto the map's ", lattice.width, "x",
                             lattice.height, " texel lattice takes ", formatBytes(latticeBytes),
                             ", more than half the memory budget of ", formatBytes(budget),
                             " (the out-of-core build holds imagery whole; use a smaller --texture-size or more "
                             "--memory)");
        }
        auto imagery = readGeoImagery(*options.texture, lattice);
        TERRAIN_TRY(imagery);
        const double texelsPerSample = (header.textureSize - 1.0) / (header.chunkSize - 1.0);
        auto covered = std::make_unique<CoveredImageTexture>(std::move(imagery.value()), texelsPerSample,
                                                             header.validX0, header.validY0, *texture.generated);
        texture.imageryCoverage = covered->coverage();
        texture.source = std::move(covered);
    } else if (options.texture) {
        auto image = readPngImage(*options.texture, 3);
        TERRAIN_TRY(image);
        texture.image = std::make_unique<Image>(std::move(image.value()));
        texture.source = std::make_unique<ImageTexture>(*texture.image, header);
    } else {
        texture.source = std::move(texture.generated);
    }
    return texture;
}

/// The weight map (-w) over the map, or null without one.
Expected<std::unique_ptr<WeightMap>> readWeights(const BuildOptions& options, const MapHeader& header)
{
    if (!options.weights) {
        return std::unique_ptr<WeightMap>();
    }
    auto image = readPngImage(*options.weights, 1);
    TERRAIN_TRY(image);
    return std::make_unique<WeightMap>(std::move(image.value()), header);
}

/// Creates the map file (under a temporary name until committed) and writes its header, patched at the end,
/// and the header's records: detail recipe, roughness, georeference.
Expected<AtomicFile> beginMapFile(const std::filesystem::path& output, const MapHeader& header)
{
    auto file = AtomicFile::create(output);
    TERRAIN_TRY(file);
    file->write(encodeHeader(header).data(), kHeaderBytes);
    if (header.detailRecipe) {
        file->write(encodeDetailRecipe(*header.detailRecipe, header.version));
    }
    if (header.roughness) {
        file->write(encodeRoughness(*header.roughness));
    }
    if (header.georeferenceBytes > 0) {
        file->write(encodeGeoreference(header.crsWkt, header.crsUnitMetres));
    }
    return file;
}

/// Appends encoded blocks to the map file: their entries, offsets made absolute, to the directory, and their
/// byte counts to the report.
class BlockWriter {
public:
    BlockWriter(AtomicFile& file, BuildReport& report, std::uint64_t nodes) : mFile(file), mReport(report)
    {
        mDirectory.reserve(nodes);
    }

    /// Appends `block` after what was written so far, and empties it.
    void append(EncodedBlock& block)
    {
        const std::uint64_t base = mFile.size();
        for (auto& entry : block.entries) {
            entry.offset += base;
            mDirectory.push_back(entry);
        }
        mFile.write(block.bytes);
        mReport.heightBytes += block.heightBytes;
        mReport.textureBytes += block.textureBytes;
        mReport.storedSamples += block.storedSamples;
        block = {};
    }

    std::vector<DirectoryEntry>& directory() { return mDirectory; }

private:
    AtomicFile& mFile;
    BuildReport& mReport;
    std::vector<DirectoryEntry> mDirectory;
};

/// Reports the nodes built out of `total` as "building nodes" progress every 100 ms, from a thread of its own,
/// until stop() (no thread without a callback).
class NodeProgress {
public:
    NodeProgress(const std::function<void(double, std::string_view)>& progress, const std::atomic<std::uint64_t>& done,
                 std::uint64_t total)
    {
        if (progress) {
            mThread = std::thread([this, &progress, &done, total] {
                while (!mStop) {
                    progress(0.05 + 0.95 * static_cast<double>(done) / static_cast<double>(total), "building nodes");
                    std::this_thread::sleep_for(std::chrono::milliseconds(100));
                }
            });
        }
    }
    NodeProgress(const NodeProgress&) = delete;
    NodeProgress& operator=(const NodeProgress&) = delete;
    ~NodeProgress() { stop(); }

    void stop()
    {
        mStop = true;
        if (mThread.joinable()) {
            mThread.join();
        }
    }

private:
    std::atomic<bool> mStop{false};
    std::thread mThread;
};

/// Builds the subtrees at the split level (partials.subtrees) on `threads` workers, each into its own block,
/// appended in subtree order; fills partials.codes, releases each subtree's square of the grid once done and
/// returns the subtree roots' summaries (the roots themselves are emitted by their parents).
std::vector<NodeSummary> buildSubtrees(const Builder& builder, SplitPartials& partials, QuantizedGrid& grid,
                                       const MapHeader& header, int threads, BlockWriter& writer)
{
    const std::vector<NodeId>& subtrees = partials.subtrees;
    std::vector<NodeSummary> summaries(subtrees.size());
    std::vector<std::unique_ptr<EncodedBlock>> pending(subtrees.size());
    std::mutex writeMutex;
    std::size_t nextToWrite = 0;
    auto none = [](const NodeId&) -> const NodeSummary* { return nullptr; };
    parallelFor(subtrees.size(), threads, [&](std::size_t i) {
        auto block = std::make_unique<EncodedBlock>();
        summaries[i] = builder.process(subtrees[i], *block, none);
        partials.codes[i] = builder.partialsOf(subtrees[i]);
        // Done with the subtree's square (and the tiles around it that its borders touched).
        const std::uint64_t side = std::uint64_t{header.chunkSize - 1} << (header.levels - 1 - partials.split);
        const std::uint64_t margin = 2 * 64;
        const std::uint64_t x0 = subtrees[i].x * side, y0 = subtrees[i].y * side;
        grid.release(x0 > margin ? x0 - margin : 0, y0 > margin ? y0 - margin : 0, x0 + side + margin,
                     y0 + side + margin);
        std::lock_guard lock(writeMutex);
        pending[i] = std::move(block);
        while (nextToWrite < pending.size() && pending[nextToWrite]) {
            writer.append(*pending[nextToWrite]);
            pending[nextToWrite].reset();
            ++nextToWrite;
        }
    });
    return summaries;
}

/// The levels above the split, reusing the subtree roots' summaries, and the root: appended last.
void buildUpperLevels(const Builder& builder, const SplitPartials& partials,
                      const std::vector<NodeSummary>& subtreeSummaries, BlockWriter& writer)
{
    const int split = partials.split;
    const std::vector<NodeId>& subtrees = partials.subtrees;
    EncodedBlock top;
    auto known = [&](const NodeId& id) -> const NodeSummary* {
        if (id.level != split || split == 0) {
            return nullptr;
        }
        auto it = std::find(subtrees.begin(), subtrees.end(), id);
        return it == subtrees.end() ? nullptr : &subtreeSummaries[static_cast<std::size_t>(it - subtrees.begin())];
    };
    NodeSummary root = split == 0 ? subtreeSummaries.front() : builder.process(NodeId::root(), top, known);
    builder.emitRoot(root, top);
    writer.append(top);
}

/// Writes the directory, sorted by node key, and the final header, then commits the file.
Status finishMapFile(AtomicFile& file, MapHeader& header, std::vector<DirectoryEntry>& directory, BuildReport& report)
{
    std::sort(directory.begin(), directory.end(),
              [](const DirectoryEntry& a, const DirectoryEntry& b) { return a.id.key() < b.id.key(); });
    auto directoryBytes = encodeDirectory(directory);
    header.nodeCount = static_cast<std::uint32_t>(directory.size());
    header.directoryOffset = file.size();
    header.directoryBytes = directoryBytes.size();
    header.directoryCrc = crc32Of(directoryBytes);
    file.write(directoryBytes);
    file.writeAt(0, encodeHeader(header).data(), kHeaderBytes);
    report.fileBytes = file.size();
    return file.commit();
}

/// The report's node and leaf figures, from the directory in its order (so they do not depend on the thread
/// count).
void summarizeNodes(const std::vector<DirectoryEntry>& directory, BuildReport& report)
{
    report.nodes = directory.size();
    double detailSum = 0.0;
    for (const DirectoryEntry& entry : directory) {
        if (!entry.hasChildren) {
            ++report.leaves;
            report.maxLeafDetailError = std::max(report.maxLeafDetailError, entry.detailDeltaC);
            detailSum += entry.detailDeltaC;
        }
    }
    report.meanLeafDetailError = detailSum / static_cast<double>(report.leaves);
}

}  // namespace

std::uint64_t effectiveMemoryBudget(const BuildOptions& options)
{
    return options.memoryBudget ? options.memoryBudget : availableMemoryBytes() / 2;
}

Expected<BuildReport> buildMap(HeightField field, const BuildOptions& options, const std::filesystem::path& output)
{
    FieldRows rows(std::move(field));
    return buildMap(rows, options, output);
}

Expected<BuildReport> buildMap(HeightRows& source, const BuildOptions& options, const std::filesystem::path& output)
{
    const auto start = std::chrono::steady_clock::now();
    // Before the build: an output that cannot be created would only fail when the map is written.
    TERRAIN_TRY(checkOutputPath(output));
    const Warn warn = [&](const std::string& message) {
        if (options.warn) {
            options.warn(message);
        }
    };
    auto progress = [&](double fraction, std::string_view stage) {
        if (options.progress) {
            options.progress(fraction, stage);
        }
    };
    const HeightField& info = source.info();
    TERRAIN_TRY(checkBuildOptions(options, info));
    auto units = resolveUnits(info, options, warn);
    TERRAIN_TRY(units);
    const double scale = units->scale;
    auto headerOfInput = headerFor(info, options, units->spacing);
    TERRAIN_TRY(headerOfInput);
    MapHeader header = std::move(headerOfInput.value());
    const bool roughness = measuresRoughness(header, options, warn);
    const bool pifs = options.heightCoding == kHeightCodingPifs;

    // Memory: the whole input and grid when they fit the budget, else bands of rows and the grid in a
    // scratch file next to the output, released region by region (docs/design.md, "Out-of-core prep").
    const std::uint64_t budget = effectiveMemoryBudget(options);
    auto memory = planMemory(header,
                             {budget, options.threads, source.held() != nullptr, roughness, pifs,
                              options.forceOutOfCore, source.readsThroughGdalCache()},
                             warn);
    TERRAIN_TRY(memory);
    const int threads = memory->threads;
    if (!memory->inMemory && options.note) {
        options.note("out of core in bands of " + std::to_string(memory->coreRows) + " rows on " +
                     std::to_string(threads) + " thread(s), anonymous memory estimated at " +
                     formatBytes(memory->estimatedBytes) + " (budget " + formatBytes(budget) + ")");
    }
    InputRows input{source, nullptr, {memory->inMemory, memory->coreRows, {}}};
    HeightField whole;
    if (memory->inMemory) {
        TERRAIN_TRY(holdInput(source, whole));
        input.field = &whole;
    }
    const double baseOffset = info.verticalOffset + options.offset;
    auto clamp = clampInNativeUnits(options, baseOffset, scale);
    TERRAIN_TRY(clamp);
    input.plan.clampNative = *clamp;
    if (input.field) {
        clampSamples(input.field->samples, input.plan);
    }

    progress(0.0, "reading");
    auto statistics = measureInput(input, scale, baseOffset);
    TERRAIN_TRY(statistics);
    auto quantization = chooseMapQuantization(input, statistics->statistics, scale, baseOffset, options, header, warn);
    TERRAIN_TRY(quantization);
    progress(0.0, "quantizing");
    auto quantized = quantizeInput(input, header, *statistics, *quantization, scale, roughness, threads,
                                   output.has_parent_path() ? output.parent_path() : std::filesystem::path("."),
                                   memory->coarseShift);
    TERRAIN_TRY(quantized);
    QuantizedGrid& grid = quantized->grid;
    header.noDataFilled = quantized->filled;
    if (quantized->roughness) {
        setRoughness(header, *quantized->roughness);
    }
    BuildReport report;
    report.inputWidth = info.width;
    report.inputHeight = info.height;
    report.outOfCore = !memory->inMemory;
    report.memoryBudget = budget;
    report.threads = threads;
    report.estimatedBytes = memory->estimatedBytes;
    whole = {};  // the grid holds everything from here on

    if (header.quantizerBin > 1) {
        progress(0.02, "reconstructing");
        grid.reconstructLossy(header, header.quantizerBin, threads);
    }
    auto texture =
        chooseTexture(options, header, grid, quantized->lowest, quantized->highest, memory->inMemory, budget);
    TERRAIN_TRY(texture);
    report.imageryCoverage = texture->imageryCoverage;
    auto weights = readWeights(options, header);
    TERRAIN_TRY(weights);
    const TreeShape shape(header, weights->get());
    std::optional<PifsPyramid> pyramid;
    if (pifs) {
        // Seed 003's fractal code, top-down over the whole tree before the nodes' errors (which need every
        // node's stored heights and coding error).
        progress(0.03, "fractal coding");
        header.heightCoding = kHeightCodingPifs;
        pyramid.emplace(PifsPyramid::build(
            header, grid, [&](int level) { return shape.nodesAt(level); }, threads, options.zlibLevel));
        header.maxErrorBound = pyramid->maxErrorCodes() * header.heightStep + quantization->errorBound;
    }

    auto file = beginMapFile(output, header);
    TERRAIN_TRY(file);
    BuildOptions nodeOptions = options;
    if (options.detailDisplacementRangeFor) {
        nodeOptions.detailDisplacementRange = options.detailDisplacementRangeFor(header);
    }
    // Subtrees below the split are independent: workers build them in parallel, each into its own block,
    // and blocks are appended in subtree order; then the levels above them.
    SplitPartials partials;
    partials.split = splitLevel(header);
    partials.subtrees = shape.nodesAt(partials.split);
    partials.codes.resize(partials.subtrees.size());
    std::atomic<std::uint64_t> done{0};
    std::atomic<std::int64_t> detailNanoseconds{0};
    const Builder builder(header, grid, shape, *texture->source, quantized->filledSquares, partials, nodeOptions,
                          pyramid ? &*pyramid : nullptr, done, detailNanoseconds);
    BlockWriter writer(*file, report, shape.count());
    NodeProgress nodeProgress(options.progress, done, shape.count());
    const std::vector<NodeSummary> subtreeSummaries = buildSubtrees(builder, partials, grid, header, threads, writer);
    buildUpperLevels(builder, partials, subtreeSummaries, writer);
    nodeProgress.stop();
    progress(1.0, "writing directory");

    TERRAIN_TRY(finishMapFile(*file, header, writer.directory(), report));
    report.header = header;
    summarizeNodes(writer.directory(), report);
    report.leafDetailSeconds = static_cast<double>(detailNanoseconds.load()) * 1e-9;
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return report;
}

}  // namespace terrain
