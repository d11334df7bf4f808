// Tileable detail textures from the tileable fractal of Fractal.h (paper 3.4.5).
#include "synthesis/DetailTexture.h"

#include "core/Check.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

namespace terrain {

Image makeDetailTexture(const FractalParams& params, int size)
{
    TERRAIN_EXPECTS(size > 0, "a detail texture needs at least one pixel");
    TERRAIN_EXPECTS(params.amplitude > 0.0, "a detail texture needs a non-zero amplitude");
    FractalParams tileable = params;
    tileable.cache = FractalCache::Fractal;
    Fractal fractal(tileable);
    double step = fractal.tileSize() / size;
    Image image{size, size, 1, std::vector<std::uint8_t>(static_cast<std::size_t>(size) * size)};
    for (int y = 0; y < size; ++y) {
        for (int x = 0; x < size; ++x) {
            double v = fractal.uncachedValue(x * step, y * step) / params.amplitude;
            image.pixel(x, y)[0] = static_cast<std::uint8_t>(std::clamp(std::lround(127.5 + 127.5 * v), 0L, 255L));
        }
    }
    return image;
}

namespace {

/// The z with Phi(z) = u, u in (0, 1): bisection on the normal distribution function (erfc) over [-40, 40].
double normalQuantile(double u)
{
    double lo = -40.0, hi = 40.0;
    for (int i = 0; i < 100; ++i) {
        const double mid = 0.5 * (lo + hi);
        (0.5 * std::erfc(-mid / std::sqrt(2.0)) < u ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

}  // namespace

double meanGray(const Image& image)
{
    TERRAIN_EXPECTS(image.channels == 1 && !image.pixels.empty(), "a one-channel image with pixels");
    const double sum = std::accumulate(image.pixels.begin(), image.pixels.end(), 0.0);
    return sum / static_cast<double>(image.pixels.size()) / 255.0;
}

Image gaussianized(const Image& image)
{
    TERRAIN_EXPECTS(image.channels == 1 && !image.pixels.empty(), "a one-channel image with pixels");
    std::array<double, 256> count{};
    for (std::uint8_t p : image.pixels) {
        count[p] += 1.0;
    }
    const auto n = static_cast<double>(image.pixels.size());
    double mean = 0.0, square = 0.0;
    for (int v = 0; v < 256; ++v) {
        mean += v * count[v] / n;
        square += v * v * count[v] / n;
    }
    const double deviation = std::sqrt(std::max(square - mean * mean, 0.0));
    // Each gray's normal quantile, then the quantiles scaled to zero mean and unit deviation over the pixels
    // (ties gather a class at one quantile, which narrows the spread a little).
    std::array<double, 256> z{};
    double below = 0.0, zMean = 0.0, zSquare = 0.0;
    for (int v = 0; v < 256; ++v) {
        if (count[v] > 0.0) {
            z[v] = normalQuantile((below + 0.5 * count[v]) / n);  // the mid-rank, in (0, 1)
            zMean += z[v] * count[v] / n;
            zSquare += z[v] * z[v] * count[v] / n;
        }
        below += count[v];
    }
    const double zDeviation = std::sqrt(std::max(zSquare - zMean * zMean, 0.0));
    std::array<std::uint8_t, 256> map{};
    for (int v = 0; v < 256; ++v) {
        const double unit = zDeviation > 0.0 ? (z[v] - zMean) / zDeviation : 0.0;
        map[v] = static_cast<std::uint8_t>(std::clamp(std::round(mean + deviation * unit), 0.0, 255.0));
    }
    Image out = image;
    for (std::uint8_t& p : out.pixels) {
        p = map[p];
    }
    return out;
}

}  // namespace terrain
