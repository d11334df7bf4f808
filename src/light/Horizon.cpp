// Horizons of a height grid, and the sun's and sky's visibility from them (Horizon.h).
#include "light/Horizon.h"

#include "core/Check.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace terrain {

double HeightGrid::at(double x, double y) const
{
    TERRAIN_EXPECTS(width >= 1 && height >= 1 && heights.size() == static_cast<std::size_t>(width) * height,
                    "a grid with its samples");
    const double gx = std::clamp((x - originX) / spacing, 0.0, width - 1.0);
    const double gy = std::clamp((y - originY) / spacing, 0.0, height - 1.0);
    const int i = std::min(static_cast<int>(gx), std::max(width - 2, 0));
    const int j = std::min(static_cast<int>(gy), std::max(height - 2, 0));
    const double fx = gx - i, fy = gy - j;
    auto h = [&](int a, int b) {
        return double{heights[static_cast<std::size_t>(std::min(b, height - 1)) * width + std::min(a, width - 1)]};
    };
    return (1.0 - fy) * ((1.0 - fx) * h(i, j) + fx * h(i + 1, j)) +
           fy * ((1.0 - fx) * h(i, j + 1) + fx * h(i + 1, j + 1));
}

std::vector<float> horizonTangents(const HeightGrid& grid, double x, double y, double z, const HorizonOptions& options)
{
    TERRAIN_EXPECTS(options.azimuths >= 1 && options.maxDistance > 0.0 && options.stepGrowth > 0.0,
                    "at least one azimuth, a distance and a step growth > 0");
    std::vector<float> tangents(static_cast<std::size_t>(options.azimuths));
    for (int k = 0; k < options.azimuths; ++k) {
        const double angle = 2.0 * std::numbers::pi * k / options.azimuths;
        const double dx = std::cos(angle), dy = std::sin(angle);
        double best = -1.0;
        // Steps of a quarter spacing near the point (a slope turned from the sun shades itself within a sample),
        // then growing with the distance.
        const double fine = 0.25 * grid.spacing;
        for (double r = fine; r <= options.maxDistance; r += std::max(fine, options.stepGrowth * r)) {
            best = std::max(best, (grid.at(x + r * dx, y + r * dy) - z) / r);
        }
        tangents[static_cast<std::size_t>(k)] = static_cast<float>(best);
    }
    return tangents;
}

double sunVisibility(std::span<const float> tangents, double sunAzimuth, double sunElevation, double softness)
{
    TERRAIN_EXPECTS(!tangents.empty() && softness > 0.0, "horizons and a softness > 0");
    const auto n = static_cast<double>(tangents.size());
    double a = sunAzimuth / (2.0 * std::numbers::pi) * n;
    a -= n * std::floor(a / n);  // in [0, n)
    const auto k = std::min(static_cast<std::size_t>(a), tangents.size() - 1);
    const double f = a - static_cast<double>(k);
    const double tangent = (1.0 - f) * tangents[k] + f * tangents[(k + 1) % tangents.size()];
    const double margin = sunElevation - std::atan(tangent);
    const double t = std::clamp(0.5 + 0.5 * margin / softness, 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

double skyVisibility(std::span<const float> tangents)
{
    TERRAIN_EXPECTS(!tangents.empty(), "horizons");
    double sum = 0.0;
    for (float t : tangents) {
        const double above = std::max(double{t}, 0.0);
        sum += 1.0 / (1.0 + above * above);
    }
    return sum / static_cast<double>(tangents.size());
}

}  // namespace terrain
