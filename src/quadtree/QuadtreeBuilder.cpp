// The preprocessor (paper 4.1.1): quantize, reconstruct, simplify (3.2.3), measure errors (3.2.5, eq. 3.1)
// and bounds (3.2.12), prune (3.2.13), texture (3.2.7), code and write (3.2.14).
#include "quadtree/QuadtreeBuilder.h"

#include "core/AtomicFile.h"
#include "core/Check.h"
#include "core/Memory.h"
#include "core/ParallelFor.h"
#include "heightfield/GdalRaster.h"
#include "heightfield/NoDataFill.h"
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
#include <limits>
#include <memory>
#include <mutex>

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

/// Rows a band of the out-of-core passes reads beyond the rows it produces: the no-data fill's reach, then
/// the roughness lags measured on the filled samples.
constexpr int kBandMargin = kFillRings + kRoughnessMargin;

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

/// Calls fn(window, windowRow0, windowRows, core0, core1) for bands whose cores [core0, core1) cover the
/// field's rows in order, each window holding its core and `margin` rows beyond it on each side (as far as
/// the field goes): the held field at once, or bands read from the source.
Status forEachBand(HeightRows& source, HeightField* field, const InputPlan& plan, int margin,
                   const std::function<Status(std::span<float>, int, int, int, int)>& fn)
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

/// The split level the parallel subtrees start at: deep enough for every core to be busy (64 subtrees) and
/// for a subtree's square to stay within 4096 samples (what the out-of-core build holds per thread). The
/// tree alone decides it, so the file does not depend on the thread count or on the memory budget.
int splitLevel(const MapHeader& header)
{
    const int levels = static_cast<int>(header.levels);
    int split = std::min(3, levels - 1);
    while (split < levels - 1 && (std::uint64_t{header.chunkSize - 1} << (levels - 1 - split)) > 4096) {
        ++split;
    }
    return split;
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
    auto warn = [&](const std::string& message) {
        if (options.warn) {
            options.warn(message);
        }
    };
    auto progress = [&](double fraction, std::string_view stage) {
        if (options.progress) {
            options.progress(fraction, stage);
        }
    };
    if (!isValidChunkSize(options.chunkSize)) {
        return makeError("chunk size ", options.chunkSize, " must be 2^k+1 between 3 and ", kMaxChunkSize,
                         " (e.g. 33, 65, 129)");
    }
    const int textureSize = options.textureSize == 0 ? options.chunkSize : options.textureSize;
    if (!isPowerOfTwoPlusOne(textureSize) || textureSize > kMaxTextureSize) {
        return makeError("texture size ", textureSize, " must be 2^k+1 between 3 and ", kMaxTextureSize,
                         " (e.g. 65, 129, 257)");
    }
    if (options.threads < 1) {
        return makeError("thread count ", options.threads, " must be at least 1");
    }
    // The worker threads: options.threads, fewer out of core where the memory budget holds no more.
    int threads = options.threads;
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
    const HeightField& info = source.info();
    if (info.width < 2 || info.height < 2) {
        return makeError("height field is ", info.width, "x", info.height, "; at least 2x2 samples are needed");
    }

    // Spacing and vertical scale: the file's own win (paper 4.4.1), the options fill in what it lacks.
    double spacing = 1.0;
    if (info.spacing) {
        spacing = *info.spacing;
        if (options.spacing && *options.spacing != spacing) {
            warn("-h " + std::to_string(*options.spacing) + " has no effect: the file gives a spacing of " +
                 std::to_string(spacing) + " m");
        }
    } else if (options.spacing) {
        spacing = *options.spacing;
    } else {
        warn("the file gives no sample spacing and -h was not given: using 1 m");
    }
    if (!(spacing >= kMinSpacingMetres && spacing <= kMaxSpacingMetres)) {
        return makeError("sample spacing ", spacing, " m", info.spacing ? " (the file's)" : "", " must be in [",
                         kMinSpacingMetres, ", ", kMaxSpacingMetres, "] m");
    }
    double scale = 1.0;
    if (info.verticalScale) {
        scale = *info.verticalScale;
        if (options.verticalScale && *options.verticalScale != scale) {
            warn("-v " + std::to_string(*options.verticalScale) +
                 " has no effect: the file gives a vertical scale of " + std::to_string(scale));
        }
    } else if (options.verticalScale) {
        scale = *options.verticalScale;
    }
    if (!std::isfinite(options.offset)) {
        return makeError("offset ", options.offset, " must be a finite number");
    }

    const int width = info.width, height = info.height;
    MapHeader header;
    header.chunkSize = static_cast<std::uint32_t>(options.chunkSize);
    header.textureSize = static_cast<std::uint32_t>(textureSize);
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
    const auto gridSize = static_cast<std::uint32_t>(header.gridSize());
    const int cells = options.chunkSize - 1;
    const std::uint64_t leavesPerSide = std::uint64_t{1} << (header.levels - 1);
    const bool roughness = options.measureRoughness && header.levels <= 15;
    if (options.measureRoughness && !roughness) {
        warn("a map of " + std::to_string(header.levels) +
             " levels is too large for a roughness grid: the detail below its leaves will not continue the "
             "terrain's roughness");
    }

    // Memory: the whole input and grid when they fit the budget, else bands of rows and the grid in a
    // scratch file next to the output, released region by region (docs/design.md, "Out-of-core prep").
    const std::uint64_t budget = effectiveMemoryBudget(options);
    const std::uint64_t samples = std::uint64_t{static_cast<std::uint32_t>(width)} * static_cast<std::uint32_t>(height);
    const std::uint64_t fixedBytes = leavesPerSide * leavesPerSide * (1 + (roughness ? 80 : 0));
    const std::uint64_t inMemoryBytes =
        (source.held() ? 0 : samples * 4) + samples * 2 + QuantizedGrid::storageBytes(gridSize) + fixedBytes;
    InputPlan plan;
    plan.inMemory = inMemoryBytes <= budget && !options.forceOutOfCore;
    if (pifs && !plan.inMemory) {
        return makeError("--height-codec pifs builds in memory, and a ", width, "x", height, " input needs about ",
                         formatBytes(inMemoryBytes + QuantizedGrid::storageBytes(gridSize) * 4 / 3),
                         (options.forceOutOfCore ? std::string(" (--out-of-core was given)")
                                                 : ", more than the memory budget of " + formatBytes(budget)),
                         ": use the residual codec out of core");
    }
    // Out of core, the samples the nodes above the split read (multiples of the split level's stride) stay
    // in memory beside the scratch file (QuantizedGrid::createMapped).
    const int coarseShift =
        std::min(QuantizedGrid::kTileShift, static_cast<int>(header.levels) - 1 - splitLevel(header));
    if (!plan.inMemory) {
        // Bands: a quarter of the budget for the band (samples, fill and mask bytes), at least a leaf row and
        // 256 rows; per thread a subtree's square of codes and its encoded nodes.
        const std::uint64_t rowBytes = std::uint64_t{static_cast<std::uint32_t>(width)} * 6;
        // The rows of a band for a budget, and what the build then needs: the band grows with the budget.
        auto coreRowsFor = [&](std::uint64_t b) {
            const std::uint64_t bandRows = std::max<std::uint64_t>(b / 4 / rowBytes, 1);
            const int leafRowsPerBand = static_cast<int>(
                std::max<std::uint64_t>({bandRows > 2 * kBandMargin ? (bandRows - 2 * kBandMargin) / cells : 0,
                                         static_cast<std::uint64_t>(256 / cells), std::uint64_t{1}}));
            return leafRowsPerBand * cells;
        };
        const std::uint64_t square = std::min<std::uint64_t>(gridSize, 4096 + 2 * cells);
        const std::uint64_t perThread = square * square * 6;  // its codes, encoded nodes and textures
        auto neededFor = [&](std::uint64_t b) {
            return (static_cast<std::uint64_t>(coreRowsFor(b)) + 2 * kBandMargin) * rowBytes +
                   static_cast<std::uint64_t>(threads) * perThread + fixedBytes +
                   samples / (kFillBlock * kFillBlock) * 16 + QuantizedGrid::coarseLatticeBytes(gridSize, coarseShift) +
                   (std::uint64_t{4} << 20);
        };
        plan.coreRows = coreRowsFor(budget);
        // Each thread holds a subtree's square: as many as fit, saying so when fewer than asked.
        while (threads > 1 && neededFor(budget) > budget) {
            --threads;
        }
        if (threads < options.threads) {
            warn("building on " + std::to_string(threads) + " thread(s) of the " + std::to_string(options.threads) +
                 " asked: each holds a subtree of the grid, and more do not fit the memory budget of " +
                 formatBytes(budget));
        }
        if (neededFor(budget) > budget) {
            // The least budget that covers what it itself needs (the need grows by a quarter of the budget, so
            // following the need converges), rounded up to a MiB: following the advice works.
            std::uint64_t advice = neededFor(budget);
            for (int k = 0; k < 200 && neededFor(advice) > advice; ++k) {
                advice = neededFor(advice);
            }
            if (!options.forceOutOfCore) {
                advice = std::min(advice, inMemoryBytes);  // the whole build in memory may need less
            }
            advice = (advice + (std::uint64_t{1} << 20) - 1) >> 20 << 20;
            return makeError("the memory budget of ", formatBytes(budget), " is too small for a ", width, "x", height,
                             " input even out of core on one thread: --memory ", advice >> 20, "M is enough");
        }
    }
    HeightField whole;
    HeightField* field = nullptr;
    if (plan.inMemory) {
        if (HeightField* held = source.held()) {
            whole = std::move(*held);
        } else {
            TERRAIN_TRY(checkAllocation(samples * 4,
                                        "a " + std::to_string(width) + "x" + std::to_string(height) + " height field"));
            whole = info;
            whole.samples.resize(samples);
            TERRAIN_TRY(source.readRows(0, height, whole.samples));
        }
        field = &whole;
    }
    if (options.clampMetres) {
        const double base = info.verticalOffset + options.offset;
        const auto [lo, hi] = *options.clampMetres;
        if (!(lo <= hi && std::abs(lo) <= kMaxHeightMetres && std::abs(hi) <= kMaxHeightMetres)) {
            return makeError("--clamp ", lo, ",", hi, ": LO <= HI, both within +-", kMaxHeightMetres, " m");
        }
        auto native = [&](double metres) {
            constexpr double kMax = std::numeric_limits<float>::max();
            return static_cast<float>(std::clamp((metres - base) / scale, -kMax, kMax));
        };
        plan.clampNative = std::array<float, 2>{native(lo), native(hi)};
        if (field) {
            clampSamples(field->samples, plan);
        }
    }

    // Pass 1: the valid samples' statistics and the far fill's block means.
    progress(0.0, "reading");
    SampleStatistics statistics(width, height);
    FarFillBuilder farBuilder(width, height);
    TERRAIN_TRY(
        forEachBand(source, field, plan, 0, [&](std::span<float> rows, int, int, int core0, int core1) -> Status {
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
    TERRAIN_TRY(checkSampleRange(statistics, scale, info.verticalOffset + options.offset));
    const FarFillGrid far = statistics.valid() < samples ? farBuilder.finish() : FarFillGrid{};

    auto quantization = chooseQuantization(
        statistics, info.integerSamples, scale, info.verticalOffset + options.offset, options.maxError,
        [&](double g) -> Expected<std::optional<double>> {
            // Pass 1b, for float input that may lie on a lattice: every valid sample's distance from it.
            std::optional<double> worst = 0.0;
            TERRAIN_TRY(forEachBand(source, field, plan, 0, [&](std::span<float> rows, int, int, int core0, int core1) {
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

    // Pass 2: fill, roughness, codes (the padding replicating the last column and row), filled squares.
    progress(0.0, "quantizing");
    auto grid =
        plan.inMemory
            ? QuantizedGrid::create(gridSize)
            : QuantizedGrid::createMapped(
                  gridSize, output.has_parent_path() ? output.parent_path() : std::filesystem::path("."), coarseShift);
    TERRAIN_TRY(grid);
    std::optional<LeafRoughnessMeter> meter;
    if (roughness) {
        meter.emplace(width, height, scale, header);
    }
    std::vector<std::uint8_t> filledSquares(leavesPerSide * leavesPerSide, 0);
    std::uint64_t filled = 0;
    std::uint16_t lowest = 65535, highest = 0;
    std::vector<std::uint8_t> mask;
    TERRAIN_TRY(forEachBand(
        source, field, plan, kBandMargin, [&](std::span<float> rows, int w0, int wrows, int core0, int core1) {
            if (statistics.valid() < samples) {
                fillNoDataRows(rows, width, wrows, w0, far, &mask);
            }
            for (int y = core0; y < core1 && !mask.empty(); ++y) {
                const std::uint8_t* row = mask.data() + static_cast<std::size_t>(y - w0) * width;
                for (int x = 0; x < width; ++x) {
                    if (!row[x]) {
                        continue;
                    }
                    ++filled;
                    // The finest squares whose closed square holds (x, y): up to four at a corner.
                    for (int sy = y / cells - (y % cells == 0 ? 1 : 0); sy <= y / cells; ++sy) {
                        for (int sx = x / cells - (x % cells == 0 ? 1 : 0); sx <= x / cells; ++sx) {
                            if (sx >= 0 && sy >= 0 && std::uint64_t(sx) < leavesPerSide &&
                                std::uint64_t(sy) < leavesPerSide) {
                                filledSquares[std::uint64_t(sy) * leavesPerSide + std::uint64_t(sx)] = 1;
                            }
                        }
                    }
                }
            }
            if (meter) {
                const int ly0 = core0 / cells;
                const int ly1 = core1 == height ? meter->leafRows() : core1 / cells;
                meter->addLeafRows(ly0, ly1, rows, w0, wrows, threads);
            }
            parallelFor(static_cast<std::size_t>(core1 - core0), threads, [&](std::size_t k) {
                const int y = core0 + static_cast<int>(k);
                const float* row = rows.data() + static_cast<std::size_t>(y - w0) * width;
                for (int x = 0; x < width; ++x) {
                    grid->at(static_cast<std::uint64_t>(x), static_cast<std::uint64_t>(y)) =
                        quantizeNative(row[x], *quantization);
                }
                const std::uint16_t last =
                    grid->at(static_cast<std::uint64_t>(width - 1), static_cast<std::uint64_t>(y));
                for (std::uint32_t x = static_cast<std::uint32_t>(width); x < gridSize; ++x) {
                    grid->at(x, static_cast<std::uint64_t>(y)) = last;
                }
            });
            for (int y = core0; y < core1; ++y) {
                for (int x = 0; x < width; ++x) {
                    const std::uint16_t code = grid->at(static_cast<std::uint64_t>(x), static_cast<std::uint64_t>(y));
                    lowest = std::min(lowest, code);
                    highest = std::max(highest, code);
                }
            }
            grid->release(0, static_cast<std::uint64_t>(core0) & ~std::uint64_t{63}, gridSize,
                          static_cast<std::uint64_t>(core1));
            return Status{};
        }));
    for (std::uint32_t y = static_cast<std::uint32_t>(height); y < gridSize; ++y) {
        for (std::uint32_t x = 0; x < gridSize; ++x) {
            grid->at(x, y) = grid->at(x, static_cast<std::uint64_t>(height - 1));
        }
        if (y % 256 == 255) {
            grid->release(0, (y - 255) & ~std::uint32_t{63}, gridSize, y + 1);
        }
    }
    grid->releaseAll();
    header.noDataFilled = filled;
    if (meter) {
        setRoughness(header, meter->finish());
    }
    BuildReport report;
    report.inputWidth = width;
    report.inputHeight = height;
    report.outOfCore = !plan.inMemory;
    report.memoryBudget = budget;
    report.threads = threads;
    whole = {};  // the grid holds everything from here on
    mask = {};

    if (header.quantizerBin > 1) {
        progress(0.02, "reconstructing");
        grid->reconstructLossy(header, header.quantizerBin, threads);
    }

    // -t: georeferenced imagery aligned by coordinates over the generated colours, or a PNG stretched over
    // the input.
    std::unique_ptr<TextureSource> textureSource;
    std::unique_ptr<TextureSource> generated =
        std::make_unique<HeightColouring>(*grid, header, header.heightOf(lowest), header.heightOf(highest));
    Image textureImage;
    if (options.texture && isGeoreferencedRaster(*options.texture)) {
        // The finest level's texel lattice over the valid region.
        const double texelsPerSample = (header.textureSize - 1.0) / (header.chunkSize - 1.0);
        RasterGrid lattice;
        lattice.width = static_cast<int>(std::ceil((header.validWidth - 1.0) * texelsPerSample - 1e-9)) + 1;
        lattice.height = static_cast<int>(std::ceil((header.validHeight - 1.0) * texelsPerSample - 1e-9)) + 1;
        lattice.step = header.sampleSpacing / texelsPerSample;
        lattice.x0 = header.originX + header.validX0 * header.sampleSpacing;
        lattice.y0 = header.originY + header.validY0 * header.sampleSpacing;
        lattice.crsWkt = header.crsWkt;
        lattice.crsUnitMetres = header.crsUnitMetres;
        const std::uint64_t latticeBytes =
            std::uint64_t{static_cast<std::uint32_t>(lattice.width)} * static_cast<std::uint32_t>(lattice.height) * 4;
        if (!plan.inMemory && latticeBytes > budget / 2) {
            return makeError(options.texture->string(), ": imagery resampled onto the map's ", lattice.width, "x",
                             lattice.height, " texel lattice takes ", formatBytes(latticeBytes),
                             ", more than half the memory budget of ", formatBytes(budget),
                             " (the out-of-core build holds imagery whole; use a smaller --texture-size or more "
                             "--memory)");
        }
        auto imagery = readGeoImagery(*options.texture, lattice);
        TERRAIN_TRY(imagery);
        auto covered = std::make_unique<CoveredImageTexture>(std::move(imagery.value()), texelsPerSample,
                                                             header.validX0, header.validY0, *generated);
        report.imageryCoverage = covered->coverage();
        textureSource = std::move(covered);
    } else if (options.texture) {
        auto image = readPngImage(*options.texture, 3);
        TERRAIN_TRY(image);
        textureImage = std::move(image.value());
        textureSource = std::make_unique<ImageTexture>(textureImage, header);
    } else {
        textureSource = std::move(generated);
    }
    std::unique_ptr<WeightMap> weights;
    if (options.weights) {
        auto image = readPngImage(*options.weights, 1);
        TERRAIN_TRY(image);
        weights = std::make_unique<WeightMap>(std::move(image.value()), header);
    }
    const TreeShape shape(header, weights.get());
    const std::uint64_t totalNodes = shape.count();
    std::optional<PifsPyramid> pyramid;
    if (pifs) {
        // Seed 003's fractal code, top-down over the whole tree before the nodes' errors (which need every
        // node's stored heights and coding error).
        progress(0.03, "fractal coding");
        header.heightCoding = kHeightCodingPifs;
        pyramid.emplace(PifsPyramid::build(
            header, *grid, [&](int level) { return shape.nodesAt(level); }, threads, options.zlibLevel));
        header.maxErrorBound = pyramid->maxErrorCodes() * header.heightStep + quantization->errorBound;
    }

    auto file = AtomicFile::create(output);
    TERRAIN_TRY(file);
    file->write(encodeHeader(header).data(), kHeaderBytes);  // patched at the end
    if (header.detailRecipe) {
        file->write(encodeDetailRecipe(*header.detailRecipe, header.version));
    }
    if (header.roughness) {
        file->write(encodeRoughness(*header.roughness));
    }
    if (header.georeferenceBytes > 0) {
        file->write(encodeGeoreference(header.crsWkt, header.crsUnitMetres));
    }

    std::atomic<std::uint64_t> done{0};
    std::atomic<std::int64_t> detailNanoseconds{0};
    BuildOptions nodeOptions = options;
    if (options.detailDisplacementRangeFor) {
        nodeOptions.detailDisplacementRange = options.detailDisplacementRangeFor(header);
    }
    // Subtrees below the split are independent: workers build them in parallel, each into its own block,
    // and blocks are appended in subtree order.
    SplitPartials partials;
    partials.split = splitLevel(header);
    partials.subtrees = shape.nodesAt(partials.split);
    partials.codes.resize(partials.subtrees.size());
    const int split = partials.split;
    const std::vector<NodeId>& subtrees = partials.subtrees;
    Builder builder(header, *grid, shape, *textureSource, filledSquares, partials, nodeOptions,
                    pyramid ? &*pyramid : nullptr, done, detailNanoseconds);
    std::vector<DirectoryEntry> directory;
    directory.reserve(totalNodes);
    auto append = [&](EncodedBlock& block) {
        const std::uint64_t base = file->size();
        for (auto& entry : block.entries) {
            entry.offset += base;
            directory.push_back(entry);
        }
        file->write(block.bytes);
        report.heightBytes += block.heightBytes;
        report.textureBytes += block.textureBytes;
        report.storedSamples += block.storedSamples;
        block = {};
    };

    std::vector<NodeSummary> subtreeSummaries(subtrees.size());
    std::vector<std::unique_ptr<EncodedBlock>> pending(subtrees.size());
    std::mutex writeMutex;
    std::size_t nextToWrite = 0;
    auto none = [](const NodeId&) -> const NodeSummary* { return nullptr; };
    std::atomic<bool> stopProgress{false};
    std::thread progressThread;
    if (options.progress) {
        progressThread = std::thread([&] {
            while (!stopProgress) {
                progress(0.05 + 0.95 * static_cast<double>(done) / static_cast<double>(totalNodes), "building nodes");
                std::this_thread::sleep_for(std::chrono::milliseconds(100));
            }
        });
    }
    parallelFor(subtrees.size(), threads, [&](std::size_t i) {
        auto block = std::make_unique<EncodedBlock>();
        subtreeSummaries[i] = builder.process(subtrees[i], *block, none);
        partials.codes[i] = builder.partialsOf(subtrees[i]);
        // Done with the subtree's square (and the tiles around it that its borders touched).
        const std::uint64_t side = std::uint64_t{header.chunkSize - 1} << (header.levels - 1 - split);
        const std::uint64_t margin = 2 * 64;
        const std::uint64_t x0 = subtrees[i].x * side, y0 = subtrees[i].y * side;
        grid->release(x0 > margin ? x0 - margin : 0, y0 > margin ? y0 - margin : 0, x0 + side + margin,
                      y0 + side + margin);
        std::lock_guard lock(writeMutex);
        pending[i] = std::move(block);
        while (nextToWrite < pending.size() && pending[nextToWrite]) {
            append(*pending[nextToWrite]);
            pending[nextToWrite].reset();
            ++nextToWrite;
        }
    });
    // The levels above the split, reusing the subtree roots' summaries.
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
    append(top);
    stopProgress = true;
    if (progressThread.joinable()) {
        progressThread.join();
    }
    progress(1.0, "writing directory");

    std::sort(directory.begin(), directory.end(),
              [](const DirectoryEntry& a, const DirectoryEntry& b) { return a.id.key() < b.id.key(); });
    auto directoryBytes = encodeDirectory(directory);
    header.nodeCount = static_cast<std::uint32_t>(directory.size());
    header.directoryOffset = file->size();
    header.directoryBytes = directoryBytes.size();
    header.directoryCrc = crc32Of(directoryBytes);
    file->write(directoryBytes);
    file->writeAt(0, encodeHeader(header).data(), kHeaderBytes);
    report.fileBytes = file->size();
    TERRAIN_TRY(file->commit());

    report.header = header;
    report.nodes = directory.size();
    double detailSum = 0.0;  // in directory order, so the figures do not depend on the thread count
    for (const DirectoryEntry& entry : directory) {
        if (!entry.hasChildren) {
            ++report.leaves;
            report.maxLeafDetailError = std::max(report.maxLeafDetailError, entry.detailDeltaC);
            detailSum += entry.detailDeltaC;
        }
    }
    report.meanLeafDetailError = detailSum / static_cast<double>(report.leaves);
    report.leafDetailSeconds = static_cast<double>(detailNanoseconds.load()) * 1e-9;
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return report;
}

}  // namespace terrain
