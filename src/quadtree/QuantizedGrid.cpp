#include "quadtree/QuantizedGrid.h"

#include "core/Check.h"
#include "core/Memory.h"
#include "core/ParallelFor.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace terrain {

namespace {
constexpr double kMaxCodes = 65535.0;
/// Codes spanned by non-integer data, leaving room for the lossy margin below 65535.
constexpr double kFloatCodes = 65000.0;

}  // namespace

SampleStatistics::SampleStatistics(int width, int height)
    : mWidth(width),
      mStride(
          std::max<std::uint64_t>(1, std::uint64_t(std::max(width, 0)) * std::uint64_t(std::max(height, 0)) / 65536)),
      mLo(std::numeric_limits<double>::infinity()),
      mHi(-std::numeric_limits<double>::infinity())
{
}

void SampleStatistics::addRows(int j0, int rows, std::span<const float> samples)
{
    TERRAIN_EXPECTS(samples.size() >= static_cast<std::size_t>(rows) * mWidth, "width samples per row");
    for (int r = 0; r < rows; ++r) {
        const std::uint64_t rowStart = static_cast<std::uint64_t>(j0 + r) * mWidth;
        const float* row = samples.data() + static_cast<std::size_t>(r) * mWidth;
        for (int x = 0; x < mWidth; ++x) {
            const float v = row[x];
            if (std::isnan(v)) {
                continue;
            }
            if (std::isinf(v)) {
                if (mInfinite++ == 0) {
                    mFirstInfinite = v;
                    mFirstInfiniteAt = {x, j0 + r};
                }
                continue;
            }
            if (v < mLo) {
                mLo = v;
                mLoAt = {x, j0 + r};
            }
            if (v > mHi) {
                mHi = v;
                mHiAt = {x, j0 + r};
            }
            ++mValid;
            if ((rowStart + x) % mStride == 0) {
                mSubsample.push_back(v);
            }
        }
    }
}

Status checkSampleRange(const SampleStatistics& statistics, double scale, double baseOffset)
{
    TERRAIN_EXPECTS(statistics.valid() > 0 && scale > 0.0, "valid samples and a positive scale");
    auto sample = [](std::array<int, 2> at) {
        return "sample (" + std::to_string(at[0]) + ", " + std::to_string(at[1]) +
               ") (column, row from the south-west corner)";
    };
    if (statistics.infinite() > 0) {
        const bool positive = statistics.firstInfinite() > 0;
        return makeError(statistics.infinite(), " sample(s) are infinite, the first ", positive ? "+inf" : "-inf",
                         " at ", sample(statistics.firstInfiniteAt()), ": if they mark missing data, give --nodata ",
                         positive ? "inf" : "-inf", "; to keep them within a range, --clamp LO,HI (metres)");
    }
    // The terrain's bulk: from the subsample's median (every sample of a small field) up and down as long as
    // no gap between consecutive values is wider than g = 10 median absolute deviations, at least 10 km (no
    // relief on Earth has such a gap, and an island missed by the subsample is not taken for a spike).
    std::vector<double> s = statistics.subsample();
    if (s.empty()) {
        s.push_back(statistics.lo());
    }
    std::sort(s.begin(), s.end());
    const std::size_t middle = s.size() / 2;
    const double median = s[middle];
    std::vector<double> deviation(s.size());
    std::transform(s.begin(), s.end(), deviation.begin(), [&](double v) { return std::abs(v - median); });
    std::nth_element(deviation.begin(), deviation.begin() + static_cast<std::ptrdiff_t>(middle), deviation.end());
    const double g = std::max(10.0 * deviation[middle], 1e4 / scale);
    std::size_t top = middle, bottom = middle;
    while (top + 1 < s.size() && s[top + 1] - s[top] <= g) {
        ++top;
    }
    while (bottom > 0 && s[bottom] - s[bottom - 1] <= g) {
        --bottom;
    }
    const double q0 = s[bottom], q1 = s[top], fence = g;
    auto metres = [&](double native) { return baseOffset + scale * native; };
    auto outlier = [&](bool high) {
        const double v = high ? statistics.hi() : statistics.lo();
        char value[64];
        std::snprintf(value, sizeof value, "%.9g", v);  // a float's value exactly as --nodata reads it
        char range[160];
        std::snprintf(range, sizeof range, "which lies within %.6g m to %.6g m", metres(q0), metres(q1));
        return makeError("the ", high ? "highest" : "lowest", " sample, ", value, " (", metres(v), " m) at ",
                         sample(high ? statistics.hiAt() : statistics.loAt()), ", lies far ", high ? "above" : "below",
                         " the rest of the terrain (", range, "): if it marks missing data, give --nodata ", value,
                         "; to keep it within a range, --clamp LO,HI (metres)");
    };
    if (statistics.hi() > q1 + fence) {
        return outlier(true);
    }
    if (statistics.lo() < q0 - fence) {
        return outlier(false);
    }
    const double lo = metres(statistics.lo()), hi = metres(statistics.hi());
    if (!(std::abs(lo) <= kMaxHeightMetres && std::abs(hi) <= kMaxHeightMetres)) {
        return makeError("the heights range from ", lo, " m to ", hi, " m (vertical scale ", scale, ", offset ",
                         baseOffset, " m): beyond +-", kMaxHeightMetres, " m; check -v and --offset");
    }
    // 65535 height steps over the relief must stay apart where the heights lie: a relief finer than 2^-30 of
    // its distance from 0 would quantize to steps that doubles (and the viewer's positions) cannot resolve.
    const double relief = hi - lo, magnitude = std::max(std::abs(lo), std::abs(hi));
    if (relief > 0.0 && relief < std::ldexp(magnitude, -30)) {
        return makeError("the heights span only ", relief, " m at ", lo, " m (vertical scale ", scale, ", offset ",
                         baseOffset, " m): finer than positions resolve that far from 0; check -v and --offset");
    }
    return {};
}

double latticeTolerance(double lo, double hi)
{
    // Float32 rounding of the samples: a few units in the last place of the largest magnitude.
    return 4.0 * std::ldexp(std::max({std::abs(lo), std::abs(hi), 1.0}), -23);
}

std::optional<double> estimateLattice(const SampleStatistics& statistics)
{
    const double lo = statistics.lo(), hi = statistics.hi();
    const double range = hi - lo;
    const double tolerance = latticeTolerance(lo, hi);
    if (!(range > 64 * tolerance) || statistics.valid() < 16) {
        return std::nullopt;
    }
    // The step is first estimated from the smallest gap between distinct values of the subsample, then
    // refined on values ever farther from lo (each k known exactly from the estimate before).
    std::vector<double> values = statistics.subsample();
    values.push_back(hi);
    std::sort(values.begin(), values.end());
    double gap = range;
    for (std::size_t k = 1; k < values.size(); ++k) {
        const double d = values[k] - values[k - 1];
        if (d > 8 * tolerance) {
            gap = std::min(gap, d);
        }
    }
    double g = gap;
    if (range / g + 1 > kMaxCodes) {
        return std::nullopt;
    }
    for (double span : {8.0, 64.0, 512.0, 4096.0, 32768.0, 1e9}) {
        // The value whose lattice index is nearest `span` (the largest for the last round).
        const double target = std::min(lo + span * g, hi);
        const auto it = std::lower_bound(values.begin(), values.end(), target);
        const double v = it == values.end() ? hi : *it;
        const double k = std::round((v - lo) / g);
        if (k >= 1) {
            g = (v - lo) / k;
        }
    }
    return g;
}

std::optional<double> latticeDeviation(std::span<const float> samples, double lo, double hi, double g)
{
    const double tolerance = latticeTolerance(lo, hi);
    double worst = 0.0;
    for (float sample : samples) {
        if (std::isnan(sample)) {
            continue;
        }
        const double d = sample - lo;
        const double deviation = std::abs(d - std::round(d / g) * g);
        if (deviation > tolerance + 1e-6 * g) {
            return std::nullopt;
        }
        worst = std::max(worst, deviation);
    }
    return worst;
}

Expected<Quantization> chooseQuantization(const SampleStatistics& statistics, bool integerSamples, double scale,
                                          double baseOffset, double maxError,
                                          const std::function<Expected<std::optional<double>>(double)>& latticeWorst)
{
    if (!(scale > 0) || !std::isfinite(scale)) {
        return makeError("vertical scale ", scale, " must be a positive finite number");
    }
    if (!(maxError >= 0) || !std::isfinite(maxError)) {
        return makeError("maximum error ", maxError, " must be a finite number >= 0");
    }
    TERRAIN_EXPECTS(statistics.valid() > 0, "some sample must be valid");
    const double lo = statistics.lo(), hi = statistics.hi();
    TERRAIN_EXPECTS(std::isfinite(lo) && std::isfinite(hi), "finite samples (checkSampleRange)");
    const double range = hi - lo;

    Quantization q;
    q.nativeMin = lo;
    std::optional<double> lattice;
    std::optional<double> latticeError;
    if (!(integerSamples && range + 1 <= kMaxCodes) && maxError == 0) {
        lattice = estimateLattice(statistics);
        if (lattice) {
            auto worst = latticeWorst(*lattice);
            TERRAIN_TRY(worst);
            latticeError = *worst;
        }
    }
    if (integerSamples && range + 1 <= kMaxCodes) {
        // Lossless: one code per native unit; the lossy margin must still fit.
        q.nativePerCode = 1.0;
        q.step = scale;
        // In double first: a huge maxError must not overflow the cast.
        const auto e = static_cast<std::uint32_t>(
            std::min(std::floor(maxError / q.step + 1e-9), std::floor((kMaxCodes - range) / 2)));
        q.margin = e;
        q.bin = 2 * e + 1;
        q.errorBound = e * q.step;
    } else if (lattice && latticeError) {
        // Float samples on a lattice: one code per lattice step, no error beyond the samples' own rounding.
        q.nativePerCode = *lattice;
        q.step = q.nativePerCode * scale;
        q.margin = 0;
        q.bin = 1;
        q.errorBound = *latticeError * scale;
    } else {
        // Non-integer data: the finest step that fits 16 bits, rounding adds half a step of error.
        q.nativePerCode = std::max(range, 1e-9) / kFloatCodes;
        for (;;) {
            q.step = q.nativePerCode * scale;
            double remaining = maxError - q.step / 2;
            auto e = remaining > 0
                         ? static_cast<std::uint32_t>(std::min(std::floor(remaining / q.step + 1e-9), kMaxCodes))
                         : 0u;
            if (range / q.nativePerCode + 2.0 * e + 1 <= kMaxCodes) {
                q.margin = e;
                q.bin = 2 * e + 1;
                q.errorBound = q.step / 2 + e * q.step;
                break;
            }
            q.nativePerCode *= 1.05;
        }
    }
    q.offset = baseOffset + scale * lo - q.step * q.margin;
    return q;
}

Expected<Quantization> chooseQuantization(const HeightField& field, double scale, double baseOffset, double maxError)
{
    SampleStatistics statistics(field.width, field.height);
    statistics.addRows(0, field.height, field.samples);
    if (statistics.valid() == 0) {
        return makeError("height field has no valid sample (every sample is no-data)");
    }
    if (!(scale > 0) || !std::isfinite(scale)) {
        return makeError("vertical scale ", scale, " must be a positive finite number");
    }
    TERRAIN_TRY(checkSampleRange(statistics, scale, baseOffset));
    return chooseQuantization(statistics, field.integerSamples, scale, baseOffset, maxError,
                              [&](double g) -> Expected<std::optional<double>> {
                                  return latticeDeviation(field.samples, statistics.lo(), statistics.hi(), g);
                              });
}

std::uint16_t quantizeNative(double native, const Quantization& q)
{
    const double code = std::round((native - q.nativeMin) / q.nativePerCode) + q.margin;
    return static_cast<std::uint16_t>(std::clamp(code, 0.0, kMaxCodes));
}

std::uint64_t QuantizedGrid::storageBytes(std::uint32_t size)
{
    const std::uint64_t tiles = (std::uint64_t{size} + kTileMask) >> kTileShift;
    return (tiles * tiles << (2 * kTileShift)) * sizeof(std::uint16_t);
}

QuantizedGrid::QuantizedGrid(std::uint32_t size) : mSize(size), mTilesX((std::uint64_t{size} + kTileMask) >> kTileShift)
{
}

Expected<QuantizedGrid> QuantizedGrid::create(std::uint32_t size)
{
    TERRAIN_TRY(checkAllocation(storageBytes(size),
                                "the " + std::to_string(size) + "x" + std::to_string(size) + " quantized height grid"));
    QuantizedGrid grid(size);
    grid.mHeap.assign(storageBytes(size) / sizeof(std::uint16_t), 0);
    grid.mData = grid.mHeap.data();
    return grid;
}

std::uint64_t QuantizedGrid::coarseLatticeBytes(std::uint32_t size, int coarseShift)
{
    const std::uint64_t side = ((std::uint64_t{size} - 1) >> coarseShift) + 1;
    return side * side * sizeof(std::uint16_t);
}

Expected<QuantizedGrid> QuantizedGrid::createMapped(std::uint32_t size, const std::filesystem::path& directory,
                                                    int coarseShift)
{
    TERRAIN_EXPECTS(coarseShift >= 0 && coarseShift <= kTileShift, "coarse lattice shift out of range");
    auto mapping = ScratchMapping::create(directory, storageBytes(size));
    TERRAIN_TRY(mapping);
    QuantizedGrid grid(size);
    grid.mMapping.emplace(std::move(mapping.value()));
    grid.mData = static_cast<std::uint16_t*>(grid.mMapping->data());
    grid.mLatticeShift = coarseShift;
    grid.mLatticeMask = (std::uint64_t{1} << coarseShift) - 1;
    grid.mLatticeSide = ((std::uint64_t{size} - 1) >> coarseShift) + 1;
    grid.mLatticeHeap.assign(grid.mLatticeSide * grid.mLatticeSide, 0);
    grid.mLattice = grid.mLatticeHeap.data();
    grid.mNoLattice = 0;
    return grid;
}

void QuantizedGrid::release(std::uint64_t x0, std::uint64_t y0, std::uint64_t x1, std::uint64_t y1) const
{
    if (!mMapping) {
        return;
    }
    auto firstTile = [](std::uint64_t v) { return (v + kTileMask) >> kTileShift; };
    auto endTile = [&](std::uint64_t v) { return v >= mSize ? mTilesX : v >> kTileShift; };
    const std::uint64_t tx0 = firstTile(x0), tx1 = endTile(x1);
    const std::uint64_t ty0 = firstTile(y0), ty1 = endTile(y1);
    constexpr std::uint64_t tileBytes = (std::uint64_t{1} << (2 * kTileShift)) * sizeof(std::uint16_t);
    for (std::uint64_t ty = ty0; ty < ty1 && tx0 < tx1; ++ty) {
        mMapping->release((ty * mTilesX + tx0) * tileBytes, (tx1 - tx0) * tileBytes);
    }
}

Expected<QuantizedGrid> QuantizedGrid::build(const HeightField& field, const Quantization& q, std::uint32_t size)
{
    TERRAIN_EXPECTS(size >= static_cast<std::uint32_t>(std::max(field.width, field.height)),
                    "grid must be at least as large as the field");
    auto grid = create(size);
    TERRAIN_TRY(grid);
    for (std::uint32_t y = 0; y < size; ++y) {
        int sy = std::min<int>(static_cast<int>(y), field.height - 1);
        for (std::uint32_t x = 0; x < size; ++x) {
            int sx = std::min<int>(static_cast<int>(x), field.width - 1);
            grid->at(x, y) = quantizeNative(field.at(sx, sy), q);
        }
    }
    return grid;
}

void QuantizedGrid::extractWindow(const MapHeader& header, const NodeId& id, std::span<std::uint16_t> window) const
{
    NodeWindow geometry(header);
    const int w = geometry.size();
    const WindowRect inside = geometry.insideRect(id);
    const std::uint64_t stride = std::uint64_t{1} << (header.levels - 1 - static_cast<std::uint32_t>(id.level));
    const std::int64_t firstX = std::int64_t{id.x} * (header.chunkSize - 1) - kBorder;
    const std::int64_t firstY = std::int64_t{id.y} * (header.chunkSize - 1) - kBorder;
    for (int y = inside.y0; y <= inside.y1; ++y) {
        auto gy = static_cast<std::uint64_t>(firstY + y) * stride;
        for (int x = inside.x0; x <= inside.x1; ++x) {
            auto gx = static_cast<std::uint64_t>(firstX + x) * stride;
            window[static_cast<std::size_t>(y) * w + x] = at(gx, gy);
        }
    }
    fillOutside(window, w, inside);
}

void QuantizedGrid::reconstructLossy(const MapHeader& header, std::uint32_t bin, int threads)
{
    NodeWindow geometry(header);
    const int w = geometry.size();
    const int n = static_cast<int>(header.chunkSize);
    const int levels = static_cast<int>(header.levels);

    // Root: raster order, each sample predicted from the previous reconstructed one.
    {
        const std::uint64_t stride = std::uint64_t{1} << (levels - 1);
        std::vector<std::uint16_t> window(geometry.sampleCount());
        WindowRect inside = geometry.insideRect(NodeId::root());
        for (int y = inside.y0; y <= inside.y1; ++y) {
            for (int x = inside.x0; x <= inside.x1; ++x) {
                auto& code = at(static_cast<std::uint64_t>(x - kBorder) * stride,
                                static_cast<std::uint64_t>(y - kBorder) * stride);
                std::int32_t predicted = rootPrediction(window, w, inside, x, y);
                code = static_cast<std::uint16_t>(predicted + quantizeResidual(code - predicted, bin));
                window[static_cast<std::size_t>(y) * w + x] = code;
            }
        }
    }
    // Each level from the reconstructed level above. A child writes only the samples it owns (u, v in
    // [0, N-2], plus N-1 on the grid's far edges), so no two threads write one sample, and reads only
    // samples of the level above, which no thread writes during this level.
    for (int level = 0; level + 1 < levels; ++level) {
        const std::uint32_t side = 1u << level;
        const std::uint64_t childStride = std::uint64_t{1} << (levels - 2 - level);
        const std::uint64_t parentRows = std::uint64_t(n - 1) * 2 * childStride;  // grid rows per row of nodes
        const std::uint32_t childSide = side * 2;
        std::uint64_t releasedTo = 0;
        for (std::uint32_t row = 0; row < side; ++row) {
            parallelFor(side, threads, [&](std::size_t column) {
                NodeId id{level, static_cast<std::uint32_t>(column), row};
                std::vector<std::uint16_t> parent(geometry.sampleCount());
                std::vector<std::int32_t> prediction(geometry.sampleCount());
                extractWindow(header, id, parent);
                for (int quadrant = 0; quadrant < 4; ++quadrant) {
                    NodeId child = id.child(quadrant);
                    predictChildWindow(parent, w, n, quadrant, prediction);
                    int lastU = child.x + 1 == childSide ? n - 1 : n - 2;
                    int lastV = child.y + 1 == childSide ? n - 1 : n - 2;
                    for (int v = 0; v <= lastV; ++v) {
                        for (int u = 0; u <= lastU; ++u) {
                            if ((u & 1) == 0 && (v & 1) == 0) {
                                continue;
                            }
                            auto gx = (std::uint64_t{child.x} * (n - 1) + u) * childStride;
                            auto gy = (std::uint64_t{child.y} * (n - 1) + v) * childStride;
                            std::int32_t predicted =
                                prediction[static_cast<std::size_t>(v + kBorder) * w + u + kBorder];
                            auto& code = at(gx, gy);
                            code = static_cast<std::uint16_t>(predicted + quantizeResidual(code - predicted, bin));
                        }
                    }
                }
            });
            // The next row of nodes reads from kBorder parent samples below its square.
            const std::uint64_t nextRead = (row + 1) * parentRows;
            const std::uint64_t keepFrom =
                nextRead > kBorder * 2 * childStride ? nextRead - kBorder * 2 * childStride : 0;
            if (keepFrom > releasedTo) {
                release(0, releasedTo & ~kTileMask, mSize, keepFrom);
                releasedTo = keepFrom;
            }
        }
        releaseAll();
    }
}

}  // namespace terrain
