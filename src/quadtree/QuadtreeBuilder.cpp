// The preprocessor (paper 4.1.1): quantize, reconstruct, simplify (3.2.3), measure errors (3.2.5, eq. 3.1)
// and bounds (3.2.12), prune (3.2.13), texture (3.2.7), code and write (3.2.14).
#include "quadtree/QuadtreeBuilder.h"

#include "core/AtomicFile.h"
#include "core/Check.h"
#include "core/ParallelFor.h"
#include "heightfield/GdalRaster.h"
#include "heightfield/NoDataFill.h"
#include "quadtree/HeightCodec.h"
#include "quadtree/NodeTexture.h"
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
    float detailDeltaC = 0.0f;  ///< the error with the detail synthesized below the leaves (3.4.1)
    float leafDetail = 0.0f;    ///< the largest leaf detail error in the subtree
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

class Builder {
public:
    Builder(const MapHeader& header, const QuantizedGrid& grid, const TreeShape& shape, const TextureSource& texture,
            const std::vector<std::uint8_t>& filledMask, const BuildOptions& options, std::atomic<std::uint64_t>& done,
            std::atomic<std::int64_t>& detailNanoseconds)
        : mHeader(header),
          mGrid(grid),
          mShape(shape),
          mTexture(texture),
          mFilledMask(filledMask),
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
        mGrid.extractWindow(mHeader, id, window);
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
            std::vector<std::uint16_t> childWindow(mWindow.sampleCount());
            mGrid.extractWindow(mHeader, child, childWindow);
            emit(child,
                 encodeNodeHeights(mWindow, child, childWindow, window, mHeader.quantizerBin, mOptions.zlibLevel),
                 children[q], out);
            worstChild = std::max(worstChild, children[q].deltaC);
            worstChildDetail = std::max(worstChildDetail, children[q].detailDeltaC);
            summary.leafDetail = std::max(summary.leafDetail, children[q].leafDetail);
            summary.hasFilledNoData = summary.hasFilledNoData || children[q].hasFilledNoData;
            summary.minCode = std::min(summary.minCode, children[q].minCode);
            summary.maxCode = std::max(summary.maxCode, children[q].maxCode);
        }
        summary.deltaM = static_cast<float>(simplificationErrorCodes(mGrid, mHeader, id) * mHeader.heightStep);
        // The measured distance to the finest data, nested with max and a margin for the geomorph
        // (kErrorNesting; issue 12: eq. 3.1 summed delta_m over the levels, an upper bound of this that grows
        // with every level).
        const float direct = static_cast<float>(
            directErrorCodes(mGrid, mHeader, id, [this](const NodeId& n) { return mShape.hasChildren(n); }) *
            mHeader.heightStep);
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
        return summary;
    }

    /// Emits the root, which has no parent to be emitted by.
    void emitRoot(const NodeSummary& root, EncodedBlock& out) const
    {
        std::vector<std::uint16_t> window(mWindow.sampleCount());
        mGrid.extractWindow(mHeader, NodeId::root(), window);
        emit(NodeId::root(),
             encodeNodeHeights(mWindow, NodeId::root(), window, {}, mHeader.quantizerBin, mOptions.zlibLevel), root,
             out);
    }

private:
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

    /// Whether the node's square (edges included) holds an input sample that was no-data.
    bool containsFilledSample(const NodeId& id) const
    {
        if (mFilledMask.empty()) {
            return false;
        }
        const std::uint64_t size = std::uint64_t{mHeader.chunkSize - 1}
                                   << (mHeader.levels - 1 - static_cast<std::uint32_t>(id.level));
        const std::uint64_t x1 = std::min<std::uint64_t>(id.x * size + size, mHeader.validWidth - 1);
        const std::uint64_t y1 = std::min<std::uint64_t>(id.y * size + size, mHeader.validHeight - 1);
        for (std::uint64_t y = id.y * size; y <= y1; ++y) {
            for (std::uint64_t x = id.x * size; x <= x1; ++x) {
                if (mFilledMask[y * mHeader.validWidth + x]) {
                    return true;
                }
            }
        }
        return false;
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
    const TreeShape& mShape;
    const TextureSource& mTexture;
    const std::vector<std::uint8_t>& mFilledMask;  ///< validWidth x validHeight, empty when nothing was filled
    const BuildOptions& mOptions;
    NodeWindow mWindow;
    std::atomic<std::uint64_t>& mDone;
    std::atomic<std::int64_t>& mDetailNanoseconds;  ///< time spent in options.leafDetailError, all threads
};

}  // namespace

RoughnessGrid measureLeafRoughness(const HeightField& field, double metresPerUnit, const MapHeader& header, int threads)
{
    TERRAIN_EXPECTS(header.levels >= 1 && header.levels <= 15, "roughness grids are for maps of 1 to 15 levels");
    TERRAIN_EXPECTS(field.samples.size() == static_cast<std::size_t>(field.width) * field.height,
                    "the field must hold width x height samples");
    const int side = 1 << (header.levels - 1);
    const int cells = static_cast<int>(header.chunkSize) - 1;
    RoughnessGrid grid;
    grid.leavesPerSide = side;
    grid.laws.assign(static_cast<std::size_t>(side) * side, RoughnessLaw{});
    std::vector<std::uint8_t> measured(grid.laws.size(), 0);
    auto measure = [&](int x0, int y0, int x1, int y1, bool& enough) {
        std::array<double, kRoughnessLags.size()> rms{};
        enough = true;
        for (std::size_t k = 0; k < kRoughnessLags.size(); ++k) {
            const MidpointSums sums = midpointDeviation(field.samples, field.width, field.height, kRoughnessLags[k], x0,
                                                        y0, x1, y1, metresPerUnit);
            enough = enough && sums.count >= kMinRoughnessSamples;
            rms[k] = sums.rms();
        }
        return fitRoughnessLaw(rms);
    };
    parallelFor(grid.laws.size(), std::max(threads, 1), [&](std::size_t k) {
        const int lx = static_cast<int>(k % side), ly = static_cast<int>(k / side);
        const int x0 = std::min(lx * cells, field.width), y0 = std::min(ly * cells, field.height);
        const int x1 = lx == side - 1 ? field.width : std::min((lx + 1) * cells, field.width);
        const int y1 = ly == side - 1 ? field.height : std::min((ly + 1) * cells, field.height);
        bool enough = false;
        grid.laws[k] = measure(x0, y0, x1, y1, enough);
        measured[k] = enough ? 1 : 0;
    });
    if (std::find(measured.begin(), measured.end(), 1) == measured.end()) {
        bool enough = false;
        const RoughnessLaw whole = measure(0, 0, field.width, field.height, enough);
        std::fill(grid.laws.begin(), grid.laws.end(), whole);
        return grid;
    }
    // The others: the nearest measured leaf (squared leaf distance; ties to the lowest index).
    std::vector<int> sources;
    for (std::size_t k = 0; k < measured.size(); ++k) {
        if (measured[k]) {
            sources.push_back(static_cast<int>(k));
        }
    }
    for (std::size_t k = 0; k < measured.size(); ++k) {
        if (measured[k]) {
            continue;
        }
        const int lx = static_cast<int>(k % side), ly = static_cast<int>(k / side);
        long best = -1;
        int from = sources.front();
        for (int source : sources) {
            const long dx = source % side - lx, dy = source / side - ly;
            if (best < 0 || dx * dx + dy * dy < best) {
                best = dx * dx + dy * dy;
                from = source;
            }
        }
        grid.laws[k] = grid.laws[static_cast<std::size_t>(from)];
    }
    return grid;
}

Expected<BuildReport> buildMap(HeightField field, const BuildOptions& options, const std::filesystem::path& output)
{
    const auto start = std::chrono::steady_clock::now();
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
    if (field.width < 2 || field.height < 2) {
        return makeError("height field is ", field.width, "x", field.height, "; at least 2x2 samples are needed");
    }

    // Spacing and vertical scale: the file's own win (paper 4.4.1), the options fill in what it lacks.
    double spacing = 1.0;
    if (field.spacing) {
        spacing = *field.spacing;
        if (options.spacing && *options.spacing != spacing) {
            warn("-h " + std::to_string(*options.spacing) + " has no effect: the file gives a spacing of " +
                 std::to_string(spacing) + " m");
        }
    } else if (options.spacing) {
        spacing = *options.spacing;
    } else {
        warn("the file gives no sample spacing and -h was not given: using 1 m");
    }
    if (!(spacing > 0) || !std::isfinite(spacing)) {
        return makeError("sample spacing ", spacing, " m must be a positive finite number");
    }
    double scale = 1.0;
    if (field.verticalScale) {
        scale = *field.verticalScale;
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

    // No-data samples: filled from valid neighbours and counted.
    if (countValid(field) == 0) {
        return makeError("height field has no valid sample (every sample is no-data)");
    }
    std::vector<std::uint8_t> filledMask;
    const std::uint64_t filled = fillNoData(field, &filledMask);

    MapHeader header;
    header.chunkSize = static_cast<std::uint32_t>(options.chunkSize);
    header.textureSize = static_cast<std::uint32_t>(textureSize);
    header.levels = 1;
    while (header.gridSize() < static_cast<std::uint64_t>(std::max(field.width, field.height))) {
        ++header.levels;
    }
    if (header.levels > 24) {
        return makeError("height field of ", field.width, "x", field.height, " needs more than 24 levels");
    }
    header.sampleSpacing = spacing;
    header.originX = field.originX;
    header.originY = field.originY;
    header.validWidth = static_cast<std::uint32_t>(field.width);
    header.validHeight = static_cast<std::uint32_t>(field.height);
    header.noDataFilled = filled;
    header.source = field.description;
    setGeoreference(header, field.crsWkt, field.crsUnitMetres);
    setDetailRecipe(header, options.detailRecipe);

    if (options.measureRoughness && header.levels <= 15) {
        progress(0.0, "measuring roughness");
        setRoughness(header, measureLeafRoughness(field, scale, header, options.threads));
    } else if (options.measureRoughness) {
        warn("a map of " + std::to_string(header.levels) +
             " levels is too large for a roughness grid: the detail below its leaves will not continue the "
             "terrain's roughness");
    }

    auto quantization = chooseQuantization(field, scale, field.verticalOffset + options.offset, options.maxError);
    TERRAIN_TRY(quantization);
    header.heightOffset = quantization->offset;
    header.heightStep = quantization->step;
    header.quantizerBin = quantization->bin;
    header.maxErrorBound = quantization->errorBound;
    if (options.maxError > 0 && quantization->bin == 1 && quantization->errorBound == 0) {
        warn("--max-error " + std::to_string(options.maxError) + " m is below one height step (" +
             std::to_string(quantization->step) + " m): storing losslessly");
    }

    progress(0.0, "quantizing");
    auto grid = QuantizedGrid::build(field, *quantization, static_cast<std::uint32_t>(header.gridSize()));
    TERRAIN_TRY(grid);
    BuildReport report;
    report.inputWidth = field.width;
    report.inputHeight = field.height;
    field.samples = {};  // the grid holds everything from here on

    // Height range of the input (valid region), for the generated texture's bands.
    std::uint16_t lowest = 65535, highest = 0;
    for (std::uint32_t y = 0; y < header.validHeight; ++y) {
        for (std::uint32_t x = 0; x < header.validWidth; ++x) {
            lowest = std::min(lowest, grid->at(x, y));
            highest = std::max(highest, grid->at(x, y));
        }
    }

    if (header.quantizerBin > 1) {
        progress(0.02, "reconstructing");
        grid->reconstructLossy(header, header.quantizerBin, options.threads);
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
    Builder builder(header, *grid, shape, *textureSource, filledMask, nodeOptions, done, detailNanoseconds);
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

    // Subtrees below `split` are independent: workers build them in parallel, each into its own block,
    // and blocks are appended in subtree order. The split depends on the tree only, so the file does not
    // depend on the thread count.
    constexpr int kSplitLevel = 3;  ///< up to 64 subtrees: enough to keep any likely core count busy
    const int split = std::min(kSplitLevel, static_cast<int>(header.levels) - 1);
    const std::vector<NodeId> subtrees = shape.nodesAt(split);
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
    parallelFor(subtrees.size(), options.threads, [&](std::size_t i) {
        auto block = std::make_unique<EncodedBlock>();
        subtreeSummaries[i] = builder.process(subtrees[i], *block, none);
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
