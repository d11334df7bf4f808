#include "synthesis/RoughnessNoise.h"

#include "core/Check.h"
#include "core/SplitMix64.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace terrain {

namespace {

/// Amplitudes below this are taken as this (log A must be finite): a micrometre, nothing visible.
constexpr double kTinyAmplitude = 1e-6;
/// Lags 2^-m of a wavelength summed in the calibration: the terms fall as 2^((2H - 4) m).
constexpr int kCalibrationLags = 12;
/// Positions per lag the calibration averages over.
constexpr int kCalibrationPositions = 2048;

}  // namespace

RoughnessNoise::RoughnessNoise(RoughnessGrid grid, int leafCells, double dataSpacing, int octaves, std::uint64_t seed)
    : mGrid(std::move(grid)), mLeafCells(leafCells), mDataSpacing(dataSpacing)
{
    TERRAIN_EXPECTS(dataSpacing > 0.0 && std::isfinite(dataSpacing), "the data's spacing must be > 0");
    TERRAIN_EXPECTS(mGrid.leavesPerSide >= 1 &&
                        mGrid.laws.size() == static_cast<std::size_t>(mGrid.leavesPerSide) * mGrid.leavesPerSide,
                    "the roughness grid must hold leavesPerSide^2 laws");
    TERRAIN_EXPECTS(leafCells >= 2, "a leaf has at least 2 cells a side");
    TERRAIN_EXPECTS(octaves >= 0 && octaves <= kMaxRoughnessOctaves, "octaves must be in [0, kMaxRoughnessOctaves]");
    for (int k = 0; k < octaves; ++k) {
        mNoise.emplace_back(seed + static_cast<std::uint64_t>(k));
    }
    mLogAmplitude.reserve(mGrid.laws.size());
    for (const RoughnessLaw& law : mGrid.laws) {
        mLogAmplitude.push_back(std::log(std::max(law.amplitude, kTinyAmplitude)));
    }
    // G_{m,L}: the mean square midpoint deviation of one octave at a lag of L 2^-m cells (L in
    // kRoughnessLags), at positions a level's samples take on its lattice (whole cells plus multiples of
    // 2^-m), along x and along y, for m = 1 .. kCalibrationLags.
    const PerlinNoise noise(seed ^ 0xca11b4a7e0ull);
    constexpr std::size_t kLagCount = kRoughnessLags.size();
    std::vector<std::array<double, kLagCount>> g(kCalibrationLags + 1);
    SplitMix64 random(seed);
    for (int m = 1; m <= kCalibrationLags; ++m) {
        const double step = std::ldexp(1.0, -m);
        std::array<double, kLagCount> sums{};
        for (int p = 0; p < kCalibrationPositions; ++p) {
            const std::uint64_t r = random.next();
            const double x = static_cast<double>(r & 1023) + static_cast<double>((r >> 10) & ((1u << m) - 1)) * step;
            const double y =
                static_cast<double>((r >> 24) & 1023) + static_cast<double>((r >> 34) & ((1u << m) - 1)) * step;
            const double centre = noise(x, y);
            for (std::size_t l = 0; l < kLagCount; ++l) {
                const double lag = kRoughnessLags[l] * step;
                const double dx = centre - 0.5 * (noise(x - lag, y) + noise(x + lag, y));
                const double dy = centre - 0.5 * (noise(x, y - lag) + noise(x, y + lag));
                sums[l] += dx * dx + dy * dy;
            }
        }
        for (std::size_t l = 0; l < kLagCount; ++l) {
            g[static_cast<std::size_t>(m)][l] = sums[l] / (2.0 * kCalibrationPositions);
        }
    }
    // Level j's samples see octaves k < j, at m = j - k: at a lag of L samples, D^2 = c^2 A^2 2^(-2jH)
    // sum_m 2^(2Hm) G_{m,L}, the law's A^2 L^(2H) 2^(-2jH) for c = c_L. The grid-aligned octaves are not
    // exactly self-similar (at longer lags the finer octaves add their whole variance), so the c_L differ;
    // c is their geometric mean: the law holds on average over the lags prep fits it on.
    const int entries =
        static_cast<int>(std::lround((kMaxRoughnessExponent - kMinRoughnessExponent) / kRoughnessCalibrationStep)) + 1;
    for (int i = 0; i < entries; ++i) {
        const double h = kMinRoughnessExponent + i * kRoughnessCalibrationStep;
        double logC = 0.0;
        for (std::size_t l = 0; l < kLagCount; ++l) {
            double total = 0.0;
            for (int m = 1; m <= kCalibrationLags; ++m) {
                total += std::exp2(2.0 * h * m) * g[static_cast<std::size_t>(m)][l];
            }
            logC += std::log(std::pow(kRoughnessLags[l], h) / std::sqrt(total)) / kLagCount;
        }
        mCalibration.push_back(std::exp(logC));
    }
}

int RoughnessNoise::octavesDownTo(double dataSpacing, double finestWavelength)
{
    TERRAIN_EXPECTS(dataSpacing > 0.0 && finestWavelength > 0.0, "spacing and wavelength must be > 0");
    int octaves = 0;
    while (octaves < kMaxRoughnessOctaves && std::ldexp(dataSpacing, -octaves) >= finestWavelength) {
        ++octaves;
    }
    return octaves;
}

int RoughnessNoise::levelsBelow(double spacing) const
{
    TERRAIN_EXPECTS(spacing > 0.0, "a spacing must be > 0");
    return static_cast<int>(std::lround(std::log2(mDataSpacing / spacing)));
}

double RoughnessNoise::calibration(double exponent) const
{
    const double t = (std::clamp(exponent, kMinRoughnessExponent, kMaxRoughnessExponent) - kMinRoughnessExponent) /
                     kRoughnessCalibrationStep;
    const auto i = std::min(static_cast<std::size_t>(t), mCalibration.size() - 2);
    const double f = t - static_cast<double>(i);
    return (1.0 - f) * mCalibration[i] + f * mCalibration[i + 1];
}

RoughnessLaw RoughnessNoise::lawAt(double u, double v) const
{
    const int side = mGrid.leavesPerSide;
    // Leaf centres at (x + 0.5) leafCells.
    auto split = [&](double w, int& i0, int& i1, double& t) {
        const double f = std::clamp(w / mLeafCells - 0.5, 0.0, static_cast<double>(side - 1));
        i0 = std::min(static_cast<int>(f), side - 1);
        i1 = std::min(i0 + 1, side - 1);
        t = f - i0;
    };
    int x0, x1, y0, y1;
    double tx, ty;
    split(u, x0, x1, tx);
    split(v, y0, y1, ty);
    auto index = [&](int x, int y) { return static_cast<std::size_t>(y) * side + x; };
    auto blend = [&](auto value) {
        const double south = (1.0 - tx) * value(index(x0, y0)) + tx * value(index(x1, y0));
        const double north = (1.0 - tx) * value(index(x0, y1)) + tx * value(index(x1, y1));
        return (1.0 - ty) * south + ty * north;
    };
    RoughnessLaw law;
    law.amplitude = std::exp(blend([&](std::size_t k) { return mLogAmplitude[k]; }));
    law.exponent = blend([&](std::size_t k) { return mGrid.laws[k].exponent; });
    if (law.amplitude <= kTinyAmplitude * (1.0 + 1e-9)) {
        law.amplitude = 0.0;
    }
    return law;
}

double RoughnessNoise::deviationAt(double u, double v, double lag) const
{
    TERRAIN_EXPECTS(lag > 0.0, "a lag must be > 0");
    const RoughnessLaw law = lawAt(u, v);
    return law.amplitude * std::pow(lag / mDataSpacing, law.exponent);
}

void RoughnessNoise::deviationGrid(std::int64_t gx0, std::int64_t gy0, int width, int height, double spacing,
                                   double lag, std::span<float> out) const
{
    TERRAIN_EXPECTS(width >= 0 && height >= 0 && out.size() >= static_cast<std::size_t>(width) * height,
                    "out must hold width x height values");
    const int below = levelsBelow(spacing);
    const double toLeafLevel = std::ldexp(1.0, -below);  // exact: a power of two
    if (below <= 0 || width == 0 || height == 0) {
        for (int j = 0; j < height; ++j) {
            const double v = static_cast<double>(gy0 + j) * toLeafLevel;
            for (int i = 0; i < width; ++i) {
                out[static_cast<std::size_t>(j) * width + i] =
                    static_cast<float>(deviationAt(static_cast<double>(gx0 + i) * toLeafLevel, v, lag));
            }
        }
        return;
    }
    // Below the leaves: D at the finest static samples (a lattice fixed in the world), interpolated bilinearly
    // to the level's samples. The law varies over tens of those samples, so this is D to about 1e-4, and it
    // depends only on the sample's position: the lattice values are D at integer (u, v), the fractions are
    // exact (powers of two), so every node computes the same bits for a sample it shares.
    const std::int64_t step = std::int64_t{1} << below;
    auto floorDiv = [&](std::int64_t g) { return g >= 0 ? g / step : -((-g + step - 1) / step); };
    const std::int64_t u0 = floorDiv(gx0), u1 = floorDiv(gx0 + width - 1) + 1;
    const std::int64_t v0 = floorDiv(gy0), v1 = floorDiv(gy0 + height - 1) + 1;
    const auto lw = static_cast<std::size_t>(u1 - u0 + 1);
    std::vector<double> lattice(lw * static_cast<std::size_t>(v1 - v0 + 1));
    for (std::int64_t v = v0; v <= v1; ++v) {
        for (std::int64_t u = u0; u <= u1; ++u) {
            lattice[static_cast<std::size_t>(v - v0) * lw + static_cast<std::size_t>(u - u0)] =
                deviationAt(static_cast<double>(u), static_cast<double>(v), lag);
        }
    }
    for (int j = 0; j < height; ++j) {
        const std::int64_t gy = gy0 + j, v = floorDiv(gy);
        const double fy = static_cast<double>(gy - v * step) * toLeafLevel;
        const double* south = lattice.data() + static_cast<std::size_t>(v - v0) * lw;
        const double* north = south + lw;
        for (int i = 0; i < width; ++i) {
            const std::int64_t gx = gx0 + i, u = floorDiv(gx);
            const double fx = static_cast<double>(gx - u * step) * toLeafLevel;
            const auto c = static_cast<std::size_t>(u - u0);
            const double s0 = south[c] + fx * (south[c + 1] - south[c]);
            const double n0 = north[c] + fx * (north[c + 1] - north[c]);
            out[static_cast<std::size_t>(j) * width + i] = static_cast<float>(s0 + fy * (n0 - s0));
        }
    }
}

double RoughnessNoise::maxDeviation(double lag) const
{
    double largest = 0.0;
    for (const RoughnessLaw& law : mGrid.laws) {
        largest = std::max(largest, law.amplitude * std::pow(lag / mDataSpacing, law.exponent));
    }
    return largest * (1.0 + 1e-9);  // lawAt's exp(log A) rounds
}

void RoughnessNoise::amplitudes(double u, double v, int count, double* out) const
{
    const RoughnessLaw law = lawAt(u, v);
    const double ratio = std::exp2(-law.exponent);
    double a = calibration(law.exponent) * law.amplitude;
    for (int k = 0; k < count; ++k) {
        out[k] = a;
        a *= ratio;
    }
}

float RoughnessNoise::at(std::int64_t gx, std::int64_t gy, int below) const
{
    TERRAIN_EXPECTS(below <= 30, "at most 30 levels below the leaves");
    const int count = std::min(below, octaves());
    if (count <= 0) {
        return 0.0f;
    }
    const double toLeafLevel = std::ldexp(1.0, -below);  // exact: a power of two
    double a[kMaxRoughnessOctaves];
    amplitudes(static_cast<double>(gx) * toLeafLevel, static_cast<double>(gy) * toLeafLevel, count, a);
    float sum = 0.0f;
    for (int k = 0; k < count; ++k) {
        // Octave k's lattice has 2^m of this level's samples a cell: cell and fraction are exact.
        const int m = below - k;
        const std::int64_t mask = (std::int64_t{1} << m) - 1;
        const double scale = std::ldexp(1.0, -m);
        const float p = mNoise[static_cast<std::size_t>(k)].cell(
            gx >> m, gy >> m, static_cast<double>(gx & mask) * scale, static_cast<double>(gy & mask) * scale);
        sum += static_cast<float>(a[k]) * p;
    }
    return sum;
}

void RoughnessNoise::add(std::int64_t gx0, std::int64_t gy0, int width, int height, int below, std::span<float> out,
                         std::span<const std::uint8_t> mask) const
{
    TERRAIN_EXPECTS(width >= 0 && height >= 0 && out.size() >= static_cast<std::size_t>(width) * height,
                    "out must hold width x height values");
    TERRAIN_EXPECTS(mask.empty() || mask.size() >= static_cast<std::size_t>(width) * height,
                    "the mask must hold width x height values");
    TERRAIN_EXPECTS(below <= 30, "at most 30 levels below the leaves");
    const int count = std::min(below, octaves());
    if (count <= 0) {
        return;
    }
    // at() for batches of samples: the same operations in the same order for each, with the octaves' noise
    // evaluated 64 cells at a time (PerlinNoise::cells, bit for bit its cell32).
    constexpr int kBatch = LatticeBatch::kSize;
    const SimdPath path = bestSimdPath();
    const double toLeafLevel = std::ldexp(1.0, -below);
    std::size_t index[kBatch];
    std::int64_t sx[kBatch], sy[kBatch];
    float amplitude[kMaxRoughnessOctaves][kBatch];
    float sum[kBatch];
    LatticeBatch batch;
    float noise[kBatch];
    int filled = 0;
    auto flush = [&] {
        for (int s = filled; s < kBatch; ++s) {  // unused lanes: any valid cell
            batch.cellX[s] = batch.cellY[s] = 0;
            batch.tx[s] = batch.ty[s] = batch.u[s] = batch.v[s] = 0.0f;
        }
        for (int s = 0; s < filled; ++s) {
            sum[s] = 0.0f;
        }
        for (int k = 0; k < count; ++k) {
            const int m = below - k;
            const std::int64_t low = (std::int64_t{1} << m) - 1;
            const double scale = std::ldexp(1.0, -m);
            for (int s = 0; s < filled; ++s) {
                const double tx = static_cast<double>(sx[s] & low) * scale,
                             ty = static_cast<double>(sy[s] & low) * scale;
                batch.cellX[s] = static_cast<std::uint32_t>(sx[s] >> m);
                batch.cellY[s] = static_cast<std::uint32_t>(sy[s] >> m);
                batch.tx[s] = static_cast<float>(tx);
                batch.ty[s] = static_cast<float>(ty);
                batch.u[s] = PerlinNoise::fade(tx);
                batch.v[s] = PerlinNoise::fade(ty);
            }
            mNoise[static_cast<std::size_t>(k)].cells(batch, noise, path);
            for (int s = 0; s < filled; ++s) {
                sum[s] += amplitude[k][s] * noise[s];
            }
        }
        for (int s = 0; s < filled; ++s) {
            out[index[s]] += sum[s];
        }
        filled = 0;
    };
    for (int j = 0; j < height; ++j) {
        for (int i = 0; i < width; ++i) {
            const std::size_t k = static_cast<std::size_t>(j) * width + i;
            if (!mask.empty() && mask[k] == 0) {
                continue;
            }
            const std::int64_t gx = gx0 + i, gy = gy0 + j;
            double a[kMaxRoughnessOctaves];
            amplitudes(static_cast<double>(gx) * toLeafLevel, static_cast<double>(gy) * toLeafLevel, count, a);
            for (int o = 0; o < count; ++o) {
                amplitude[o][filled] = static_cast<float>(a[o]);
            }
            index[filled] = k;
            sx[filled] = gx;
            sy[filled] = gy;
            if (++filled == kBatch) {
                flush();
            }
        }
    }
    if (filled > 0) {
        flush();
    }
}

double RoughnessNoise::bound(int from, int x0, int y0, int x1, int y1) const
{
    const int side = mGrid.leavesPerSide;
    x0 = std::clamp(x0 - 1, 0, side - 1);
    y0 = std::clamp(y0 - 1, 0, side - 1);
    x1 = std::clamp(x1 + 1, 0, side - 1);
    y1 = std::clamp(y1 + 1, 0, side - 1);
    double amplitude = 0.0, lo = kMaxRoughnessExponent, hi = kMinRoughnessExponent;
    for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) {
            const RoughnessLaw& law = mGrid.at(x, y);
            amplitude = std::max(amplitude, law.amplitude);
            lo = std::min(lo, law.exponent);
            hi = std::max(hi, law.exponent);
        }
    }
    return octaveSum(from, amplitude, lo, hi);
}

template <typename Weight>
double RoughnessNoise::weightedOctaveSum(const Weight& weight, double amplitude, double lo, double hi) const
{
    if (amplitude == 0.0) {
        return 0.0;
    }
    // Each octave's largest c(H) 2^(-k H) over the exponents there (the calibration table's entries and
    // the ends), with a margin for the curvature between entries.
    double total = 0.0;
    for (int k = 0; k < octaves(); ++k) {
        const double w = weight(k);
        if (w == 0.0) {
            continue;
        }
        double most = 0.0;
        for (double h = lo;; h = std::min(h + kRoughnessCalibrationStep, hi)) {
            most = std::max(most, calibration(h) * std::exp2(-k * h));
            if (h >= hi) {
                break;
            }
        }
        total += w * most;
    }
    return 1.01 * amplitude * total;
}

double RoughnessNoise::octaveSum(int from, double amplitude, double lo, double hi) const
{
    return weightedOctaveSum([from](int k) { return k >= from ? 1.0 : 0.0; }, amplitude, lo, hi);
}

void RoughnessNoise::lawRange(double u0, double v0, double u1, double v1, double& amplitude, double& lo,
                              double& hi) const
{
    TERRAIN_EXPECTS(u0 <= u1 && v0 <= v1, "the rectangle must not be empty");
    // The rectangle's corners, and the leaf centres' lines (u or v = (i + 0.5) leafCells) inside it.
    auto breaks = [&](double a, double b) {
        std::vector<double> at = {a, b};
        for (int i = 0; i < mGrid.leavesPerSide; ++i) {
            const double c = (i + 0.5) * mLeafCells;
            if (c > a && c < b) {
                at.push_back(c);
            }
        }
        return at;
    };
    const std::vector<double> us = breaks(u0, u1), vs = breaks(v0, v1);
    amplitude = 0.0;
    lo = kMaxRoughnessExponent;
    hi = kMinRoughnessExponent;
    for (double u : us) {
        for (double v : vs) {
            const RoughnessLaw law = lawAt(u, v);
            amplitude = std::max(amplitude, law.amplitude);
            lo = std::min(lo, law.exponent);
            hi = std::max(hi, law.exponent);
        }
    }
    // lawAt rounds: a hair of margin on the amplitude and the exponents.
    amplitude *= 1.0 + 1e-9;
    lo = std::max(lo - 1e-9, kMinRoughnessExponent);
    hi = std::min(hi + 1e-9, kMaxRoughnessExponent);
}

double RoughnessNoise::boundOver(int from, double u0, double v0, double u1, double v1) const
{
    if (from >= octaves()) {
        return 0.0;
    }
    double amplitude = 0.0, lo = 0.0, hi = 0.0;
    lawRange(u0, v0, u1, v1, amplitude, lo, hi);
    return octaveSum(from, amplitude, lo, hi);
}

double RoughnessNoise::nodeBound(double spacing, std::int64_t firstX, std::int64_t firstY, int cells) const
{
    const int below = levelsBelow(spacing);
    const double scale = std::ldexp(1.0, -below);  // the node's samples in samples of the finest static level
    const double u0 = static_cast<double>(firstX) * scale, v0 = static_cast<double>(firstY) * scale;
    return boundOver(std::max(below, 0), u0, v0, u0 + cells * scale, v0 + cells * scale);
}

RoughnessNoise::SquareLaw RoughnessNoise::squareLaw(double spacing, std::int64_t firstX, std::int64_t firstY,
                                                    int cells) const
{
    SquareLaw out;
    out.below = levelsBelow(spacing);
    const double scale = std::ldexp(1.0, -out.below);  // the level's samples in samples of the finest static level
    const double u0 = static_cast<double>(firstX) * scale, v0 = static_cast<double>(firstY) * scale;
    lawRange(u0, v0, u0 + cells * scale, v0 + cells * scale, out.amplitude, out.lo, out.hi);
    return out;
}

double RoughnessNoise::tailWeight(int k, int below)
{
    const GradientNoiseExtremes& extremes = PerlinNoise::extremes();
    return k >= below ? extremes.peak : extremes.interpolationAt(below - k);
}

void RoughnessNoise::cellTails(double spacing, std::int64_t firstX, std::int64_t firstY, int cells,
                               std::span<float> out) const
{
    TERRAIN_EXPECTS(cells >= 1 && out.size() >= static_cast<std::size_t>(cells) * cells,
                    "out must hold cells^2 values");
    const SquareLaw law = squareLaw(spacing, firstX, firstY, cells);
    const int below = law.below;
    const GradientNoiseExtremes& extremes = PerlinNoise::extremes();
    // The octaves looked up per cell: the level's own (below: one lattice cell a sample cell), the next
    // (four), and the two coarser ones with per-cell interpolation tables (m = 1, 2).
    auto perCell = [&](int k) { return k >= below - GradientNoiseExtremes::kCellLevels && k <= below + 1; };
    // The other octaves, the same everywhere; then each per-cell octave's amplitude.
    const double uniform = weightedOctaveSum([&](int k) { return perCell(k) ? 0.0 : tailWeight(k, below); },
                                             law.amplitude, law.lo, law.hi);
    std::vector<std::pair<int, double>> octavesPerCell;
    for (int k = std::max(0, below - GradientNoiseExtremes::kCellLevels); k <= below + 1 && k < octaves(); ++k) {
        octavesPerCell.emplace_back(
            k, weightedOctaveSum([k](int o) { return o == k ? 1.0 : 0.0; }, law.amplitude, law.lo, law.hi));
    }
    for (int j = 0; j < cells; ++j) {
        const std::int64_t gy = firstY + j;
        for (int i = 0; i < cells; ++i) {
            const std::int64_t gx = firstX + i;
            double tail = uniform;
            for (const auto& [k, a] : octavesPerCell) {
                const PerlinNoise& noise = mNoise[static_cast<std::size_t>(k)];
                double w = 0.0;
                if (k == below) {
                    w = extremes.cellPeak[static_cast<std::size_t>(noise.cellGradients(gx, gy))];
                } else if (k == below + 1) {
                    for (int q = 0; q < 4; ++q) {
                        w = std::max(w, static_cast<double>(extremes.cellPeak[static_cast<std::size_t>(
                                            noise.cellGradients(2 * gx + (q & 1), 2 * gy + (q >> 1)))]));
                    }
                } else {
                    const int m = below - k, split = 1 << m;
                    const std::int64_t sub = (gy & (split - 1)) * split + (gx & (split - 1));
                    const auto combo = static_cast<std::size_t>(noise.cellGradients(gx >> m, gy >> m));
                    w = extremes.cellInterpolation[static_cast<std::size_t>(
                        m - 1)][combo * static_cast<std::size_t>(split * split) + static_cast<std::size_t>(sub)];
                }
                tail += a * w;
            }
            out[static_cast<std::size_t>(j) * cells + i] = static_cast<float>(tail * (1.0 + 1e-6));
        }
    }
}

double RoughnessNoise::bound(int from) const
{
    return bound(from, 0, 0, mGrid.leavesPerSide - 1, mGrid.leavesPerSide - 1);
}

std::shared_ptr<const RoughnessNoise> makeRoughnessNoise(const MapHeader& header, const MaterialSet* materials)
{
    if (!header.roughness) {
        return nullptr;
    }
    double finest = kRoughnessFinestWavelength;
    if (materials) {
        for (const Material& m : materials->materials()) {
            if (m.displacement) {
                finest = std::max(finest, m.fractal.wavelength);
            }
        }
    }
    return std::make_shared<const RoughnessNoise>(*header.roughness, static_cast<int>(header.chunkSize) - 1,
                                                  header.sampleSpacing,
                                                  RoughnessNoise::octavesDownTo(header.sampleSpacing, finest));
}

}  // namespace terrain
