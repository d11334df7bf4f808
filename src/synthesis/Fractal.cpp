// fBm and Musgrave's ridged multifractal ("Texturing and Modeling" [6], ch. 16) over Perlin noise or a
// bitmap, with the cached basis and cached fractal of the paper (3.3.3, "Real-time Fractals").
#include "synthesis/Fractal.h"

#include "core/Check.h"
#include "heightfield/Image.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

namespace terrain {

namespace {

/// splitmix64: a seed-derived stream of per-octave rotations and offsets.
std::uint64_t splitmix(std::uint64_t& state)
{
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

double unit(std::uint64_t& state)
{
    return static_cast<double>(splitmix(state) >> 11) * 0x1.0p-53;
}

/// Octave offsets stay below this many lattice units: large enough to decorrelate octaves, small
/// enough not to cost precision in u = c * x + offset.
constexpr double kMaxOctaveOffset = 1024.0;

/// Samples per batch of the vectorised exact path: a multiple of every vector width, so the loops need no
/// scalar remainder (which GCC's -O2 "very cheap" vectoriser also insists on). 32, 64 and 128 measured
/// within 3 % of each other.
constexpr int kBatch = LatticeBatch::kSize;
/// The vectorised path splits lattice coordinates with a 32-bit conversion: |u| < 2^31. The bound it
/// checks leaves a factor 2 for the rounding of the bound itself.
constexpr double kMaxVectorLattice = 0x1.0p30;

/// Catmull-Rom weights for fraction t.
void catmullRom(double t, double w[4])
{
    double t2 = t * t;
    double t3 = t2 * t;
    w[0] = 0.5 * (-t3 + 2.0 * t2 - t);
    w[1] = 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0);
    w[2] = 0.5 * (-3.0 * t3 + 4.0 * t2 + t);
    w[3] = 0.5 * (t3 - t2);
}

}  // namespace

std::string validateFractalParams(const FractalParams& p)
{
    std::ostringstream s;
    if (p.octaves < 1 || p.octaves > 24) {
        s << "octaves must be in [1, 24], not " << p.octaves;
    } else if (!(p.lacunarity >= 1.1 && p.lacunarity <= 8.0)) {
        s << "lacunarity must be in [1.1, 8], not " << p.lacunarity;
    } else if (!(p.gain > 0.0 && p.gain <= 1.0)) {
        s << "gain must be in (0, 1], not " << p.gain;
    } else if (!(p.wavelength > 0.0 && std::isfinite(p.wavelength))) {
        s << "wavelength must be a positive number of metres, not " << p.wavelength;
    } else if (!(p.amplitude >= 0.0 && std::isfinite(p.amplitude))) {
        s << "amplitude must be a non-negative number of metres, not " << p.amplitude;
    } else if (!(p.ridgeOffset >= 0.5 && p.ridgeOffset <= 1.5)) {
        s << "ridge offset must be in [0.5, 1.5], not " << p.ridgeOffset;
    } else if (!(p.ridgeFeedback >= 0.0 && p.ridgeFeedback <= 8.0)) {
        s << "ridge feedback must be in [0, 8], not " << p.ridgeFeedback;
    }
    return s.str();
}

// ---- BasisTable ----

BasisTable::BasisTable(int width, int height, std::vector<float> values, double texelsPerUnit, Filter filter)
    : mWidth(width), mHeight(height), mValues(std::move(values)), mTexelsPerUnit(texelsPerUnit), mFilter(filter)
{
    TERRAIN_EXPECTS(width > 0 && height > 0, "a basis table needs at least one texel");
    TERRAIN_EXPECTS(mValues.size() == static_cast<std::size_t>(width) * static_cast<std::size_t>(height),
                    "values must hold width * height texels");
    TERRAIN_EXPECTS(texelsPerUnit > 0.0, "texelsPerUnit must be positive");
    mMaskX = (width & (width - 1)) == 0 ? width - 1 : -1;
    mMaskY = (height & (height - 1)) == 0 ? height - 1 : -1;
}

BasisTable BasisTable::fromImage(const Image& gray, Filter filter)
{
    TERRAIN_EXPECTS(gray.channels == 1, "a bitmap basis is a gray image (readPngImage(path, 1))");
    TERRAIN_EXPECTS(gray.width > 0 && gray.width == gray.height, "a bitmap basis must be square");
    std::vector<float> values(gray.pixels.size());
    for (std::size_t i = 0; i < values.size(); ++i) {
        values[i] = static_cast<float>(gray.pixels[i] / 127.5 - 1.0);
    }
    return BasisTable(gray.width, gray.height, std::move(values), gray.width, filter);
}

BasisTable BasisTable::fromNoise(const PerlinNoise& noise, int samplesPerCell)
{
    TERRAIN_EXPECTS(noise.period() > 0, "only a periodic noise can be tabulated");
    TERRAIN_EXPECTS(samplesPerCell > 0, "samplesPerCell must be positive");
    int n = static_cast<int>(noise.period()) * samplesPerCell;
    std::vector<float> values(static_cast<std::size_t>(n) * static_cast<std::size_t>(n));
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            values[static_cast<std::size_t>(j) * n + i] = noise.cell(
                i / samplesPerCell, j / samplesPerCell, (i % samplesPerCell) / static_cast<double>(samplesPerCell),
                (j % samplesPerCell) / static_cast<double>(samplesPerCell));
        }
    }
    return BasisTable(n, n, std::move(values), samplesPerCell, Filter::Bilinear);
}

std::int64_t BasisTable::wrap(std::int64_t i, int size, std::int64_t mask)
{
    if (mask >= 0) {
        return i & mask;  // two's complement: also right for negative i
    }
    std::int64_t r = i % size;
    return r < 0 ? r + size : r;
}

float BasisTable::at(std::int64_t x, std::int64_t y) const
{
    return mValues[static_cast<std::size_t>(y) * static_cast<std::size_t>(mWidth) + static_cast<std::size_t>(x)];
}

double BasisTable::operator()(double u, double v) const
{
    double tx = u * mTexelsPerUnit;
    double ty = v * mTexelsPerUnit;
    std::int64_t ix = PerlinNoise::floorToInt(tx);
    std::int64_t iy = PerlinNoise::floorToInt(ty);
    double ax = tx - static_cast<double>(ix);
    double ay = ty - static_cast<double>(iy);
    if (mFilter == Filter::Bilinear) {
        std::int64_t x0 = wrap(ix, mWidth, mMaskX);
        std::int64_t y0 = wrap(iy, mHeight, mMaskY);
        std::int64_t x1 = x0 + 1 == mWidth ? 0 : x0 + 1;
        std::int64_t y1 = y0 + 1 == mHeight ? 0 : y0 + 1;
        double a = at(x0, y0) + ax * (at(x1, y0) - at(x0, y0));
        double b = at(x0, y1) + ax * (at(x1, y1) - at(x0, y1));
        return a + ay * (b - a);
    }
    double wx[4];
    double wy[4];
    catmullRom(ax, wx);
    catmullRom(ay, wy);
    std::int64_t xs[4];
    for (int i = 0; i < 4; ++i) {
        xs[i] = wrap(ix + i - 1, mWidth, mMaskX);
    }
    double result = 0.0;
    for (int j = 0; j < 4; ++j) {
        std::int64_t y = wrap(iy + j - 1, mHeight, mMaskY);
        double row = 0.0;
        for (int i = 0; i < 4; ++i) {
            row += wx[i] * at(xs[i], y);
        }
        result += wy[j] * row;
    }
    return std::clamp(result, -1.0, 1.0);
}

// ---- Fractal ----

Fractal::Fractal(const FractalParams& params) : Fractal(params, nullptr) {}

Fractal::Fractal(const FractalParams& params, std::shared_ptr<const BasisTable> bitmap)
    : mParams(params), mNoise(params.seed), mPeriodicNoise(params.seed, kCachedBasisPeriod), mTable(std::move(bitmap))
{
    std::string problem = validateFractalParams(params);
    TERRAIN_EXPECTS(problem.empty(), "FractalParams out of range (validateFractalParams says what)");

    // Octave i: frequency lacunarity^i / wavelength, weight gain^i, a seed-derived rotation and offset
    // so the lattices of successive octaves never line up ([6] ch. 16 warns of the artefacts).
    std::uint64_t state = params.seed ^ 0x5851F42D4C957F2Dull;
    double weightSum = 0.0;
    double frequency = 1.0 / params.wavelength;
    double weight = 1.0;
    for (int i = 0; i < params.octaves; ++i) {
        double angle = 2.0 * std::numbers::pi * unit(state);
        double ou = kMaxOctaveOffset * unit(state);
        double ov = kMaxOctaveOffset * unit(state);
        mOctaves.push_back(
            {std::cos(angle) * frequency, std::sin(angle) * frequency, ou, ov, weight, static_cast<float>(weight)});
        weightSum += weight;
        frequency *= params.lacunarity;
        weight *= params.gain;
    }
    // fBm: the sum lies in [-weightSum, weightSum]. Ridged: each octave in [0, offset^2] times a weight in
    // [0, 1], so the sum lies in [0, offset^2 * weightSum]; it is mapped to [-amplitude, amplitude].
    if (params.type == FractalType::Fbm) {
        mScale = params.amplitude / weightSum;
        mOffset = 0.0;
    } else {
        double top = params.ridgeOffset * params.ridgeOffset * weightSum;
        mScale = 2.0 * params.amplitude / top;
        mOffset = -params.amplitude;
    }

    if (params.cache == FractalCache::Basis && !mTable) {
        mTable = std::make_shared<BasisTable>(BasisTable::fromNoise(mPeriodicNoise, kCachedBasisSamplesPerCell));
    } else if (params.cache == FractalCache::Fractal) {
        buildCachedFractal();
    }
}

template <class Basis>
inline double Fractal::sum(const std::vector<Octave>& octaves, double x, double y, const Basis& basis) const
{
    std::size_t n = octaves.size();
    double result = 0.0;
    if (mParams.type == FractalType::Fbm) {
        for (std::size_t i = 0; i < n; ++i) {
            const Octave& o = octaves[i];
            result += o.weight * basis(i, o.cu * x - o.su * y + o.ou, o.su * x + o.cu * y + o.ov);
        }
    } else {
        double weight = 1.0;
        for (std::size_t i = 0; i < n; ++i) {
            const Octave& o = octaves[i];
            double signal =
                mParams.ridgeOffset - std::abs(basis(i, o.cu * x - o.su * y + o.ou, o.su * x + o.cu * y + o.ov));
            signal *= signal * weight;
            result += o.weight * signal;
            weight = std::clamp(signal * mParams.ridgeFeedback, 0.0, 1.0);
        }
    }
    return result * mScale + mOffset;
}

void Fractal::buildCachedFractal()
{
    // The tileable fractal: no rotation, and octave i gets round(T * lacunarity^i) whole lattice cells
    // per tile (a periodic noise with that period), so every octave repeats exactly once per tile.
    const FractalParams& p = mParams;
    mTileSize = kCachedFractalTileWavelengths * p.wavelength;
    std::int64_t finestCells = 1;
    std::uint64_t state = p.seed ^ 0xDA3E39CB94B95BDBull;
    double cells = kCachedFractalTileWavelengths;
    for (std::size_t i = 0; i < mOctaves.size(); ++i) {
        auto n = std::max<std::int64_t>(1, std::llround(cells));
        if (n * kCachedFractalSamplesPerFinestCell > kCachedFractalMaxTable) {
            break;  // finer octaves would not survive the table's resolution anyway
        }
        finestCells = n;
        mTileNoise.emplace_back(p.seed + i, n);
        double ou = kMaxOctaveOffset * unit(state);
        double ov = kMaxOctaveOffset * unit(state);
        mTileOctaves.push_back({static_cast<double>(n), 0.0, ou, ov, mOctaves[i].weight, mOctaves[i].exactWeight});
        cells *= p.lacunarity;
    }
    int size = static_cast<int>(finestCells) * kCachedFractalSamplesPerFinestCell;
    // The table holds values in tile units: u = x / tileSize. The exact weights of the full octave count
    // are kept, so cutting octaves only loses detail, never changes the scale.
    std::vector<float> values(static_cast<std::size_t>(size) * static_cast<std::size_t>(size));
    double scale = mParams.amplitude > 0.0 ? 1.0 / mParams.amplitude : 0.0;
    for (int j = 0; j < size; ++j) {
        for (int i = 0; i < size; ++i) {
            values[static_cast<std::size_t>(j) * size + i] =
                static_cast<float>(tileSum(static_cast<double>(i) / size, static_cast<double>(j) / size) * scale);
        }
    }
    mFractalTable = std::make_shared<BasisTable>(size, size, std::move(values), size, BasisTable::Filter::Bilinear);
}

double Fractal::tileSum(double u, double v) const
{
    return sum(mTileOctaves, u, v, [this](std::size_t i, double a, double b) { return mTileNoise[i](a, b); });
}

double Fractal::uncachedValue(double x, double y) const
{
    if (mFractalTable) {
        return tileSum(x / mTileSize, y / mTileSize);
    }
    if (mParams.cache == FractalCache::Basis && mTable) {
        return sum(mOctaves, x, y, [this](std::size_t, double u, double v) { return mPeriodicNoise(u, v); });
    }
    return (*this)(x, y);
}

double Fractal::operator()(double x, double y) const
{
    if (mFractalTable) {
        return mParams.amplitude * (*mFractalTable)(x / mTileSize, y / mTileSize);
    }
    if (mTable) {
        const BasisTable& table = *mTable;
        return sum(mOctaves, x, y, [&table](std::size_t, double u, double v) { return table(u, v); });
    }
    return exactValue(x, y);
}

template <class Basis>
void Fractal::grid(const SampleGrid& g, std::span<float> out, std::span<const std::uint8_t> mask,
                   const Basis& basis) const
{
    for (int j = 0; j < g.height; ++j) {
        const double y = g.y(j);
        const std::size_t row = static_cast<std::size_t>(j) * static_cast<std::size_t>(g.width);
        for (int i = 0; i < g.width; ++i) {
            if (mask.empty() || mask[row + i] != 0) {
                out[row + i] = static_cast<float>(basis(g.x(i), y));
            }
        }
    }
}

void Fractal::evaluateGrid(const SampleGrid& g, std::span<float> out, std::span<const std::uint8_t> mask) const
{
    TERRAIN_EXPECTS(g.width >= 0 && g.height >= 0, "grid size must not be negative");
    TERRAIN_EXPECTS(g.spacing > 0.0, "grid spacing must be positive");
    TERRAIN_EXPECTS(out.size() >= g.count(), "out must hold width * height samples");
    TERRAIN_EXPECTS(mask.empty() || mask.size() >= g.count(), "the mask must hold width * height entries");
    if (mFractalTable) {
        const BasisTable& table = *mFractalTable;
        double a = mParams.amplitude;
        double t = mTileSize;
        grid(g, out, mask, [&](double x, double y) { return a * table(x / t, y / t); });
    } else if (mTable) {
        const BasisTable& table = *mTable;
        grid(g, out, mask, [&](double x, double y) {
            return sum(mOctaves, x, y, [&table](std::size_t, double u, double v) { return table(u, v); });
        });
    } else {
        exactGrid(g, out, mask, bestSimdPath());
    }
}

void Fractal::evaluateGrid(const SampleGrid& g, std::span<float> out, std::span<const std::uint8_t> mask,
                           SimdPath path) const
{
    TERRAIN_EXPECTS(simdPathSupported(path), "this CPU cannot run the requested SIMD path");
    if (mFractalTable || mTable) {
        evaluateGrid(g, out, mask);  // the cached paths are scalar: one path
        return;
    }
    TERRAIN_EXPECTS(g.width >= 0 && g.height >= 0, "grid size must not be negative");
    TERRAIN_EXPECTS(g.spacing > 0.0, "grid spacing must be positive");
    TERRAIN_EXPECTS(out.size() >= g.count(), "out must hold width * height samples");
    TERRAIN_EXPECTS(mask.empty() || mask.size() >= g.count(), "the mask must hold width * height entries");
    exactGrid(g, out, mask, path);
}

// ---- The exact Perlin fractal, vectorised ----
//
// The point form (exactValue) and the batch loops (FractalKernels::exactBatch) do the same operations in
// the same order: the lattice split in double (splitLattice; PerlinNoise::operator() in the point form),
// the noise in float (PerlinNoise::cell32; PerlinNoise::cells on a batch), the fBm or ridged update in
// float, the final scale in double. The batch loops are compiled twice, for the baseline and (x86-64)
// with the AVX2 target attribute; with -ffp-contract=off and no FMA in either, all give the same bits.

namespace {

/// floor(u) split into the cell's low 32 bits, the fraction rounded to float only after the exact double
/// subtraction, and the fraction's fade: what PerlinNoise::operator() computes, for |u| < 2^31. kRound: the
/// target has SSE4.1's roundpd, so floor is one instruction; else a truncating conversion and a compare
/// (which SSE2 vectorises given -fno-trapping-math, see CMakeLists.txt). Both are the exact floor.
template <bool kRound>
[[gnu::always_inline]] inline void splitLattice(double u, std::uint32_t& cell, float& fraction, float& fade)
{
    double f;
    if constexpr (kRound) {
        f = std::floor(u);
    } else {
        double t = static_cast<double>(static_cast<std::int32_t>(u));
        f = u < t ? t - 1.0 : t;
    }
    cell = static_cast<std::uint32_t>(static_cast<std::int32_t>(f));
    double d = u - f;
    fraction = static_cast<float>(d);
    fade = PerlinNoise::fade(d);
}

[[gnu::always_inline]] inline void fbmStep(float& sum, float weight, float noise)
{
    sum += weight * noise;
}

/// Musgrave's ridged multifractal, one octave: `damping` is the previous octave's signal times the
/// feedback, clamped to [0, 1] (1 before the first octave).
[[gnu::always_inline]] inline void ridgedStep(float& sum, float& damping, float weight, float noise, float offset,
                                              float feedback)
{
    float signal = offset - std::abs(noise);
    signal *= signal * damping;
    sum += weight * signal;
    damping = std::clamp(signal * feedback, 0.0f, 1.0f);
}

/// The raw float sum mapped to [-amplitude, amplitude]; float rounding of the weights could step outside
/// by an ulp, hence the clamp.
inline double scaleSum(float sum, double scale, double offset, double amplitude)
{
    return std::clamp(static_cast<double>(sum) * scale + offset, -amplitude, amplitude);
}

}  // namespace

/// The vectorised exact path: friends of Fractal, so they can read its octaves.
struct FractalKernels {
    using Batch = void (*)(const Fractal&, const double*, const double*, float*);

    /// The raw sums (before mScale and mOffset) at the kBatch points (x[k], y[k]). Everything a loop reads
    /// besides its arrays is a local, so the vectoriser needs no alias checks. kRound: the target has
    /// roundpd (splitLattice).
    template <bool kRound>
    [[gnu::always_inline]] static inline void exactBatch(const Fractal& f, const double* x, const double* y,
                                                         float* sums, SimdPath path)
    {
        LatticeBatch lattice;
        alignas(32) float noise[kBatch];
        alignas(32) float sum[kBatch];
        alignas(32) float damping[kBatch];
        const bool ridged = f.mParams.type == FractalType::Ridged;
        const auto offset = static_cast<float>(f.mParams.ridgeOffset);
        const auto feedback = static_cast<float>(f.mParams.ridgeFeedback);
        for (int k = 0; k < kBatch; ++k) {
            sum[k] = 0.0f;
            damping[k] = 1.0f;
        }
        for (const Fractal::Octave& octave : f.mOctaves) {
            const Fractal::Octave o = octave;
            for (int k = 0; k < kBatch; ++k) {
                splitLattice<kRound>(o.cu * x[k] - o.su * y[k] + o.ou, lattice.cellX[k], lattice.tx[k], lattice.u[k]);
                splitLattice<kRound>(o.su * x[k] + o.cu * y[k] + o.ov, lattice.cellY[k], lattice.ty[k], lattice.v[k]);
            }
            f.mNoise.cells(lattice, noise, path);
            if (ridged) {
                for (int k = 0; k < kBatch; ++k) {
                    ridgedStep(sum[k], damping[k], o.exactWeight, noise[k], offset, feedback);
                }
            } else {
                for (int k = 0; k < kBatch; ++k) {
                    fbmStep(sum[k], o.exactWeight, noise[k]);
                }
            }
        }
        for (int k = 0; k < kBatch; ++k) {
            sums[k] = sum[k];
        }
    }

    static void exactBatchBaseline(const Fractal& f, const double* x, const double* y, float* sums)
    {
        exactBatch<false>(f, x, y, sums, SimdPath::Baseline);
    }

#if defined(__x86_64__)
    [[gnu::target("avx2")]] static void exactBatchAvx2(const Fractal& f, const double* x, const double* y, float* sums)
    {
        exactBatch<true>(f, x, y, sums, SimdPath::Avx2);
    }
#endif

    static Batch batch(SimdPath path)
    {
#if defined(__x86_64__)
        if (path == SimdPath::Avx2) {
            return exactBatchAvx2;
        }
#endif
        (void)path;
        return exactBatchBaseline;
    }
};

double Fractal::exactValue(double x, double y) const
{
    const auto offset = static_cast<float>(mParams.ridgeOffset);
    const auto feedback = static_cast<float>(mParams.ridgeFeedback);
    float result = 0.0f;
    float damping = 1.0f;
    for (const Octave& o : mOctaves) {
        // mNoise(u, v) splits u with a 64-bit floor: the same cell and fraction as splitLattice where
        // that applies, and exact beyond it.
        auto n = static_cast<float>(mNoise(o.cu * x - o.su * y + o.ou, o.su * x + o.cu * y + o.ov));
        if (mParams.type == FractalType::Ridged) {
            ridgedStep(result, damping, o.exactWeight, n, offset, feedback);
        } else {
            fbmStep(result, o.exactWeight, n);
        }
    }
    return scaleSum(result, mScale, mOffset, mParams.amplitude);
}

bool Fractal::fitsVectorPath(const SampleGrid& g) const
{
    double maxX = std::max(std::abs(g.x(0)), std::abs(g.x(g.width - 1)));
    double maxY = std::max(std::abs(g.y(0)), std::abs(g.y(g.height - 1)));
    for (const Octave& o : mOctaves) {
        double bound = std::abs(o.cu) * maxX + std::abs(o.su) * maxY + std::max(std::abs(o.ou), std::abs(o.ov));
        if (!(bound < kMaxVectorLattice)) {
            return false;
        }
    }
    return true;
}

void Fractal::exactGrid(const SampleGrid& g, std::span<float> out, std::span<const std::uint8_t> mask,
                        SimdPath path) const
{
    if (g.width == 0 || g.height == 0) {
        return;
    }
    if (!fitsVectorPath(g)) {
        grid(g, out, mask, [this](double x, double y) { return exactValue(x, y); });
        return;
    }
    const FractalKernels::Batch batch = FractalKernels::batch(path);
    alignas(32) double xs[kBatch];
    alignas(32) double ys[kBatch];
    alignas(32) float sums[kBatch];
    std::size_t index[kBatch];
    int n = 0;
    auto flush = [&] {
        for (int k = n; k < kBatch; ++k) {  // pad a partial batch with copies of its last sample
            xs[k] = xs[n - 1];
            ys[k] = ys[n - 1];
        }
        batch(*this, xs, ys, sums);
        for (int k = 0; k < n; ++k) {
            out[index[k]] = static_cast<float>(scaleSum(sums[k], mScale, mOffset, mParams.amplitude));
        }
        n = 0;
    };
    for (int j = 0; j < g.height; ++j) {
        const double y = g.y(j);
        const std::size_t row = static_cast<std::size_t>(j) * static_cast<std::size_t>(g.width);
        for (int i = 0; i < g.width; ++i) {
            if (mask.empty() || mask[row + i] != 0) {
                xs[n] = g.x(i);
                ys[n] = y;
                index[n] = row + i;
                if (++n == kBatch) {
                    flush();
                }
            }
        }
    }
    if (n > 0) {
        flush();
    }
}

}  // namespace terrain
