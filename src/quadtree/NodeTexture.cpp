#include "quadtree/NodeTexture.h"

#include "core/Check.h"

#include <algorithm>
#include <cmath>

namespace terrain {

namespace {

struct Colour {
    double r, g, b;
};

Colour mix(const Colour& a, const Colour& b, double t)
{
    t = std::clamp(t, 0.0, 1.0);
    return {a.r + (b.r - a.r) * t, a.g + (b.g - a.g) * t, a.b + (b.b - a.b) * t};
}

double smoothstep(double e0, double e1, double x)
{
    double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
    return t * t * (3 - 2 * t);
}

// Unlit albedo palette, linear 0..1 (hand-picked to read as meadow, forest, dry slope, rock and snow).
constexpr Colour kMeadow{0.36, 0.45, 0.22};
constexpr Colour kForest{0.20, 0.30, 0.15};
constexpr Colour kDryGround{0.50, 0.44, 0.33};
constexpr Colour kRock{0.47, 0.45, 0.42};
constexpr Colour kSteepRock{0.38, 0.36, 0.34};
constexpr Colour kSnow{0.93, 0.94, 0.96};
/// Slopes (rise over run) where ground turns to rock: about 30 to 45 degrees.
constexpr double kRockSlopeStart = 0.58;
constexpr double kRockSlopeFull = 1.0;

void toBytes(const double* c, std::uint8_t* rgb)
{
    for (int k = 0; k < 3; ++k) {
        rgb[k] = static_cast<std::uint8_t>(std::clamp(c[k], 0.0, 1.0) * 255.0 + 0.5);
    }
}

}  // namespace

HeightColouring::HeightColouring(const QuantizedGrid& grid, const MapHeader& header, double heightMin, double heightMax)
    : mGrid(grid), mTable(static_cast<std::size_t>(kTableSteps) * kTableSteps * 3)
{
    // In codes, at least one: heights far from 0 may differ by less than a double resolves there.
    mCodeMin = (heightMin - header.heightOffset) / header.heightStep;
    const double codeRange = std::max((heightMax - header.heightOffset) / header.heightStep - mCodeMin, 1.0);
    mHeightStepsPerCode = (kTableSteps - 1) / codeRange;
    mSlopeStepsPerCode = (kTableSteps - 1) * header.heightStep / (2 * header.sampleSpacing) / kTableMaxSlope;
    // The palette depends on height fraction and slope only: tabulate it once.
    for (int i = 0; i < kTableSteps; ++i) {
        const double t = i / (kTableSteps - 1.0);
        for (int j = 0; j < kTableSteps; ++j) {
            const double slope = j * kTableMaxSlope / (kTableSteps - 1.0);
            Colour c = mix(kMeadow, kForest, smoothstep(0.10, 0.35, t));
            c = mix(c, kDryGround, smoothstep(0.45, 0.65, t));
            c = mix(c, kRock, smoothstep(0.65, 0.82, t));
            c = mix(c, kSteepRock, smoothstep(kRockSlopeStart, kRockSlopeFull, slope));
            // Snow lies on the highest ground where it is not too steep to hold.
            c = mix(c, kSnow, smoothstep(0.80, 0.90, t) * (1.0 - smoothstep(0.7, 1.2, slope)));
            const double rgb[3] = {c.r, c.g, c.b};
            toBytes(rgb, &mTable[(static_cast<std::size_t>(i) * kTableSteps + j) * 3]);
        }
    }
}

const std::uint8_t* HeightColouring::colourAt(std::int64_t x, std::int64_t y) const
{
    const std::int64_t last = mGrid.size() - 1;
    x = std::clamp<std::int64_t>(x, 0, last);
    y = std::clamp<std::int64_t>(y, 0, last);
    auto code = [&](std::int64_t i, std::int64_t j) -> double {
        return mGrid.at(static_cast<std::uint64_t>(i), static_cast<std::uint64_t>(j));
    };
    const double dx = code(std::min(x + 1, last), y) - code(std::max<std::int64_t>(x - 1, 0), y);
    const double dy = code(x, std::min(y + 1, last)) - code(x, std::max<std::int64_t>(y - 1, 0));
    const double t = (code(x, y) - mCodeMin) * mHeightStepsPerCode + 0.5;
    const auto i = static_cast<int>(std::isfinite(t) ? std::clamp(t, 0.0, kTableSteps - 1.0) : 0.0);
    const auto j =
        static_cast<int>(std::min(std::sqrt(dx * dx + dy * dy) * mSlopeStepsPerCode + 0.5, kTableSteps - 1.0));
    return &mTable[(static_cast<std::size_t>(i) * kTableSteps + j) * 3];
}

void HeightColouring::colour(double gx, double gy, double footprint, std::uint8_t* rgb) const
{
    double sum[3] = {0, 0, 0};
    if (footprint <= 1.0 && gx == std::floor(gx) && gy == std::floor(gy)) {
        // A texel on a sample (leaves whose texture matches the chunk).
        std::copy_n(colourAt(static_cast<std::int64_t>(gx), static_cast<std::int64_t>(gy)), 3, rgb);
        return;
    }
    if (footprint <= 1.0) {
        // Bilinear blend of the colours at the four surrounding samples.
        auto x0 = static_cast<std::int64_t>(std::floor(gx));
        auto y0 = static_cast<std::int64_t>(std::floor(gy));
        double fx = gx - static_cast<double>(x0), fy = gy - static_cast<double>(y0);
        const double weights[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
        for (int k = 0; k < 4; ++k) {
            if (weights[k] == 0) {
                continue;
            }
            const std::uint8_t* c = colourAt(x0 + (k & 1), y0 + (k >> 1));
            for (int i = 0; i < 3; ++i) {
                sum[i] += weights[k] * c[i];
            }
        }
    } else {
        // Box average over the samples under the texel.
        auto half = footprint / 2;
        auto xa = static_cast<std::int64_t>(std::ceil(gx - half)),
             xb = static_cast<std::int64_t>(std::floor(gx + half));
        auto ya = static_cast<std::int64_t>(std::ceil(gy - half)),
             yb = static_cast<std::int64_t>(std::floor(gy + half));
        int count = 0;
        for (auto y = ya; y <= yb; ++y) {
            for (auto x = xa; x <= xb; ++x) {
                const std::uint8_t* c = colourAt(x, y);
                for (int i = 0; i < 3; ++i) {
                    sum[i] += c[i];
                }
                ++count;
            }
        }
        for (double& s : sum) {
            s /= std::max(count, 1);
        }
    }
    for (int i = 0; i < 3; ++i) {
        rgb[i] = static_cast<std::uint8_t>(std::min(sum[i] + 0.5, 255.0));
    }
}

ImageTexture::ImageTexture(const Image& rgb, const MapHeader& header) : mImage(rgb)
{
    TERRAIN_EXPECTS(rgb.channels == 3 && rgb.width >= 1 && rgb.height >= 1, "texture must be RGB");
    mScaleX = header.validWidth > 1 ? (rgb.width - 1.0) / (header.validWidth - 1.0) : 0.0;
    mScaleY = header.validHeight > 1 ? (rgb.height - 1.0) / (header.validHeight - 1.0) : 0.0;
    mX0 = header.validX0;
    mY0 = header.validY0;
}

void ImageTexture::colour(double gx, double gy, double footprint, std::uint8_t* rgb) const
{
    // Image coordinates: x east, row 0 north.
    double px = (gx - mX0) * mScaleX;
    double py = (mImage.height - 1) - (gy - mY0) * mScaleY;
    auto pixel = [&](std::int64_t x, std::int64_t y) {
        return mImage.pixel(static_cast<int>(std::clamp<std::int64_t>(x, 0, mImage.width - 1)),
                            static_cast<int>(std::clamp<std::int64_t>(y, 0, mImage.height - 1)));
    };
    double sum[3] = {0, 0, 0};
    double pixelsPerTexel = footprint * std::max(mScaleX, mScaleY);
    if (pixelsPerTexel <= 1.0) {
        auto x0 = static_cast<std::int64_t>(std::floor(px));
        auto y0 = static_cast<std::int64_t>(std::floor(py));
        double fx = px - static_cast<double>(x0), fy = py - static_cast<double>(y0);
        const double weights[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
        for (int k = 0; k < 4; ++k) {
            const std::uint8_t* p = pixel(x0 + (k & 1), y0 + (k >> 1));
            for (int i = 0; i < 3; ++i) {
                sum[i] += weights[k] * p[i] / 255.0;
            }
        }
    } else {
        double half = pixelsPerTexel / 2;
        auto xa = static_cast<std::int64_t>(std::ceil(px - half)),
             xb = static_cast<std::int64_t>(std::floor(px + half));
        auto ya = static_cast<std::int64_t>(std::ceil(py - half)),
             yb = static_cast<std::int64_t>(std::floor(py + half));
        int count = 0;
        for (auto y = ya; y <= yb; ++y) {
            for (auto x = xa; x <= xb; ++x) {
                const std::uint8_t* p = pixel(x, y);
                for (int i = 0; i < 3; ++i) {
                    sum[i] += p[i] / 255.0;
                }
                ++count;
            }
        }
        for (double& s : sum) {
            s /= std::max(count, 1);
        }
    }
    toBytes(sum, rgb);
}

CoveredImageTexture::CoveredImageTexture(Image rgba, double pixelsPerSample, double x0, double y0,
                                         const TextureSource& fallback)
    : mImage(std::move(rgba)), mPixelsPerSample(pixelsPerSample), mX0(x0), mY0(y0), mFallback(fallback)
{
    TERRAIN_EXPECTS(mImage.channels == 4 && mImage.width >= 1 && mImage.height >= 1, "imagery must be RGBA");
    TERRAIN_EXPECTS(pixelsPerSample > 0, "imagery needs a positive resolution");
}

void CoveredImageTexture::colour(double gx, double gy, double footprint, std::uint8_t* rgb) const
{
    const double px = (gx - mX0) * mPixelsPerSample;
    const double py = (mImage.height - 1) - (gy - mY0) * mPixelsPerSample;
    const auto x0 = static_cast<std::int64_t>(std::floor(px));
    const auto y0 = static_cast<std::int64_t>(std::floor(py));
    const double fx = px - static_cast<double>(x0), fy = py - static_cast<double>(y0);
    const double weights[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
    double sum[3] = {0, 0, 0};
    double covered = 0.0;
    for (int k = 0; k < 4; ++k) {
        const std::int64_t x = x0 + (k & 1), y = y0 + (k >> 1);
        if (weights[k] == 0.0 || x < 0 || y < 0 || x >= mImage.width || y >= mImage.height) {
            continue;  // off the lattice (padding): not covered
        }
        const std::uint8_t* p = mImage.pixel(static_cast<int>(x), static_cast<int>(y));
        const double w = weights[k] * p[3] / 255.0;
        covered += w;
        for (int i = 0; i < 3; ++i) {
            sum[i] += w * p[i];
        }
    }
    std::uint8_t under[3] = {0, 0, 0};
    if (covered < 1.0 - 1e-9) {
        mFallback.colour(gx, gy, footprint, under);
    }
    const double rest = std::max(0.0, 1.0 - covered);
    for (int i = 0; i < 3; ++i) {
        rgb[i] = static_cast<std::uint8_t>(std::clamp(std::lround(sum[i] + rest * under[i]), 0L, 255L));
    }
}

double CoveredImageTexture::coverage() const
{
    std::size_t full = 0;
    const std::size_t count = static_cast<std::size_t>(mImage.width) * mImage.height;
    for (std::size_t k = 0; k < count; ++k) {
        full += mImage.pixels[k * 4 + 3] == 255 ? 1 : 0;
    }
    return static_cast<double>(full) / static_cast<double>(count);
}

void sampleNodeTexture(const TextureSource& source, const MapHeader& header, const NodeId& id,
                       std::span<std::uint8_t> rgb)
{
    const int size = static_cast<int>(header.textureSize);
    TERRAIN_EXPECTS(rgb.size() == static_cast<std::size_t>(size) * size * 3, "texture must have size*size RGB texels");
    const double stride = std::ldexp(1.0, static_cast<int>(header.levels) - 1 - id.level);
    const double samplesPerTexel = stride * (header.chunkSize - 1) / (size - 1);
    const double x0 = static_cast<double>(id.x) * (header.chunkSize - 1) * stride;
    const double y0 = static_cast<double>(id.y) * (header.chunkSize - 1) * stride;
    for (int ty = 0; ty < size; ++ty) {
        for (int tx = 0; tx < size; ++tx) {
            source.colour(x0 + tx * samplesPerTexel, y0 + ty * samplesPerTexel, samplesPerTexel,
                          &rgb[(static_cast<std::size_t>(ty) * size + tx) * 3]);
        }
    }
}

void downsampleChildTextures(const std::array<std::span<const std::uint8_t>, 4>& children, int size,
                             std::span<std::uint8_t> parent)
{
    TERRAIN_EXPECTS(parent.size() == static_cast<std::size_t>(size) * size * 3,
                    "texture must have size*size RGB texels");
    // The four children side by side (their shared edges coincide): (2 size - 1)^2 RGB texels.
    const int combined = 2 * size - 1;
    const std::size_t rowBytes = static_cast<std::size_t>(combined) * 3;
    std::vector<std::uint8_t> all(rowBytes * combined);
    for (int q = 0; q < 4; ++q) {
        const int x0 = (q & 1) * (size - 1), y0 = (q >> 1) * (size - 1);
        for (int y = 0; y < size; ++y) {
            std::copy_n(&children[q][static_cast<std::size_t>(y) * size * 3], static_cast<std::size_t>(size) * 3,
                        &all[static_cast<std::size_t>(y0 + y) * rowBytes + static_cast<std::size_t>(x0) * 3]);
        }
    }
    // Horizontal [1 2 1] at even columns (edge columns copied), then vertical at even rows (edge rows
    // copied): both nodes sharing an edge filter it only along itself, from identical texels.
    std::vector<std::uint16_t> horizontal(static_cast<std::size_t>(combined) * size * 3);
    for (int y = 0; y < combined; ++y) {
        const std::uint8_t* row = &all[static_cast<std::size_t>(y) * rowBytes];
        std::uint16_t* out = &horizontal[static_cast<std::size_t>(y) * size * 3];
        for (int c = 0; c < 3; ++c) {
            out[c] = static_cast<std::uint16_t>(4 * row[c]);
            out[(size - 1) * 3 + c] = static_cast<std::uint16_t>(4 * row[(combined - 1) * 3 + c]);
        }
        for (int tx = 1; tx < size - 1; ++tx) {
            const std::uint8_t* p = row + (2 * tx) * 3;
            for (int c = 0; c < 3; ++c) {
                out[tx * 3 + c] = static_cast<std::uint16_t>(p[c - 3] + 2 * p[c] + p[c + 3]);
            }
        }
    }
    const std::size_t stride = static_cast<std::size_t>(size) * 3;
    for (int ty = 0; ty < size; ++ty) {
        const std::uint16_t* mid = &horizontal[static_cast<std::size_t>(2 * ty) * stride];
        std::uint8_t* out = &parent[static_cast<std::size_t>(ty) * stride];
        if (ty == 0 || ty == size - 1) {
            for (std::size_t i = 0; i < stride; ++i) {
                out[i] = static_cast<std::uint8_t>((mid[i] + 2) / 4);
            }
            continue;
        }
        const std::uint16_t* below = mid - stride;
        const std::uint16_t* above = mid + stride;
        for (std::size_t i = 0; i < stride; ++i) {
            out[i] = static_cast<std::uint8_t>((below[i] + 2 * mid[i] + above[i] + 8) / 16);
        }
    }
}

}  // namespace terrain
