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

double unit(std::uint64_t& state) { return static_cast<double>(splitmix(state) >> 11) * 0x1.0p-53; }

/// Octave offsets stay below this many lattice units: large enough to decorrelate octaves, small
/// enough not to cost precision in u = c * x + offset.
constexpr double kMaxOctaveOffset = 1024.0;

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
            values[static_cast<std::size_t>(j) * n + i] =
                static_cast<float>(noise.cell(i / samplesPerCell, j / samplesPerCell,
                                              (i % samplesPerCell) / static_cast<double>(samplesPerCell),
                                              (j % samplesPerCell) / static_cast<double>(samplesPerCell)));
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
        mOctaves.push_back({std::cos(angle) * frequency, std::sin(angle) * frequency, ou, ov, weight});
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
        mTable = std::make_shared<BasisTable>(
            BasisTable::fromNoise(mPeriodicNoise, kCachedBasisSamplesPerCell));
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
            double signal = mParams.ridgeOffset -
                            std::abs(basis(i, o.cu * x - o.su * y + o.ou, o.su * x + o.cu * y + o.ov));
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
        mTileOctaves.push_back({static_cast<double>(n), 0.0, ou, ov, mOctaves[i].weight});
        cells *= p.lacunarity;
    }
    int size = static_cast<int>(finestCells) * kCachedFractalSamplesPerFinestCell;
    // The table holds values in tile units: u = x / tileSize. The exact weights of the full octave count
    // are kept, so cutting octaves only loses detail, never changes the scale.
    std::vector<float> values(static_cast<std::size_t>(size) * static_cast<std::size_t>(size));
    double scale = mParams.amplitude > 0.0 ? 1.0 / mParams.amplitude : 0.0;
    for (int j = 0; j < size; ++j) {
        for (int i = 0; i < size; ++i) {
            values[static_cast<std::size_t>(j) * size + i] = static_cast<float>(
                tileSum(static_cast<double>(i) / size, static_cast<double>(j) / size) * scale);
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
    return sum(mOctaves, x, y, [this](std::size_t, double u, double v) { return mNoise(u, v); });
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
        grid(g, out, mask, [&](double x, double y) {
            return sum(mOctaves, x, y, [this](std::size_t, double u, double v) { return mNoise(u, v); });
        });
    }
}

}  // namespace terrain
