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

void HeightGrid::setTop()
{
    top = heights.empty() ? 0.0 : double{*std::max_element(heights.begin(), heights.end())};
}

std::vector<float> horizonTangents(const HeightGrid& grid, double x, double y, double z, const HorizonOptions& options)
{
    std::vector<float> tangents(static_cast<std::size_t>(std::max(options.azimuths, 0)));
    horizonTangents(grid, x, y, z, options, tangents);
    return tangents;
}

void horizonTangents(const HeightGrid& grid, double x, double y, double z, const HorizonOptions& options,
                     std::span<float> tangents)
{
    TERRAIN_EXPECTS(options.azimuths >= 1 && options.maxDistance > 0.0 && options.stepGrowth > 0.0,
                    "at least one azimuth, a distance and a step growth > 0");
    TERRAIN_EXPECTS(tangents.size() == static_cast<std::size_t>(options.azimuths), "one tangent an azimuth");
    TERRAIN_EXPECTS(
        grid.width >= 2 && grid.height >= 2 &&
            grid.heights.size() == static_cast<std::size_t>(grid.width) * static_cast<std::size_t>(grid.height),
        "a grid of at least 2 x 2 samples");
    // Grid coordinates: inside the grid a bilinear lookup needs no clamping (at() does it outside).
    const double px = (x - grid.originX) / grid.spacing, py = (y - grid.originY) / grid.spacing;
    const double maxX = grid.width - 1.0, maxY = grid.height - 1.0;
    const float* h = grid.heights.data();
    const auto w = static_cast<std::size_t>(grid.width);
    for (int k = 0; k < options.azimuths; ++k) {
        const double angle = 2.0 * std::numbers::pi * k / options.azimuths;
        const double dx = std::cos(angle), dy = std::sin(angle);
        double best = -1.0;
        // Steps of a quarter spacing near the point (a slope turned from the sun shades itself within a sample),
        // then growing with the distance; none further once even the grid's top would not rise above the best.
        const double fine = 0.25 * grid.spacing;
        // The most any step from r on can see: (top - z) / r, or where the top lies below the point, what it
        // tends to at the search's end.
        const double rise = grid.top - z;
        auto mayRise = [&](double r) { return rise > best * (rise >= 0.0 ? r : options.maxDistance); };
        for (double r = fine; r <= options.maxDistance && mayRise(r); r += std::max(fine, options.stepGrowth * r)) {
            const double gx = px + r / grid.spacing * dx, gy = py + r / grid.spacing * dy;
            double height = 0.0;
            if (gx >= 0.0 && gy >= 0.0 && gx < maxX && gy < maxY) {
                const auto i = static_cast<std::size_t>(gx), j = static_cast<std::size_t>(gy);
                const double fx = gx - static_cast<double>(i), fy = gy - static_cast<double>(j);
                const float* p = h + j * w + i;
                height = (1.0 - fy) * ((1.0 - fx) * p[0] + fx * p[1]) + fy * ((1.0 - fx) * p[w] + fx * p[w + 1]);
            } else {
                height = grid.at(x + r * dx, y + r * dy);
            }
            best = std::max(best, (height - z) / r);
        }
        tangents[static_cast<std::size_t>(k)] = static_cast<float>(best);
    }
}

double sunVisibility(std::span<const float> tangents, double sunAzimuth, double sunElevation, double softness)
{
    TERRAIN_EXPECTS(!tangents.empty() && softness > 0.0 && std::isfinite(sunAzimuth) && std::isfinite(sunElevation),
                    "horizons, a softness > 0 and a sun");
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

namespace {
constexpr double kLowestHorizon = -std::numbers::pi / 4.0;
constexpr double kHorizonRange = std::numbers::pi / 2.0 - kLowestHorizon;
}  // namespace

std::uint8_t encodeHorizon(double tangent)
{
    const double angle = std::isnan(tangent) ? kLowestHorizon : std::atan(tangent);
    return static_cast<std::uint8_t>(
        std::lround(std::clamp((angle - kLowestHorizon) / kHorizonRange, 0.0, 1.0) * 255.0));
}

double decodeHorizon(std::uint8_t code)
{
    return std::tan(std::min(kLowestHorizon + kHorizonRange * code / 255.0, 0.4999 * std::numbers::pi));
}

HorizonLattice latticeQuadrant(const HorizonLattice& lattice, int quadrant)
{
    TERRAIN_EXPECTS(lattice.size >= 3 && (lattice.size - 1) % 2 == 0 && quadrant >= 0 && quadrant < 4,
                    "a lattice of 2k + 1 points and a quadrant 0..3");
    const int half = (lattice.size - 1) / 2, size = half + 1;
    const int i0 = (quadrant & 1) * half, j0 = (quadrant >> 1) * half;
    const auto a = static_cast<std::size_t>(lattice.azimuths);
    HorizonLattice q{size, lattice.azimuths, std::vector<std::uint8_t>(static_cast<std::size_t>(size) * size * a)};
    for (int j = 0; j < size; ++j) {
        for (int i = 0; i < size; ++i) {
            const auto from = (static_cast<std::size_t>(j0 + j) * lattice.size + (i0 + i)) * a;
            std::copy_n(lattice.codes.begin() + static_cast<std::ptrdiff_t>(from), a,
                        q.codes.begin() + static_cast<std::ptrdiff_t>((static_cast<std::size_t>(j) * size + i) * a));
        }
    }
    return q;
}

void latticeVisibility(const HorizonLattice& lattice, double sunAzimuth, double sunElevation, double softness, int n,
                       std::span<std::uint8_t> out, int stride, int offset)
{
    const auto l = static_cast<std::size_t>(lattice.size), a = static_cast<std::size_t>(lattice.azimuths);
    TERRAIN_EXPECTS(lattice.size >= 2 && lattice.azimuths >= 1 && lattice.codes.size() == l * l * a && n >= 2 &&
                        stride >= 2 && offset >= 0 && offset + 2 <= stride &&
                        out.size() >= static_cast<std::size_t>(n) * n * static_cast<std::size_t>(stride),
                    "a lattice with its codes, and room for n x n visibilities");
    // The visibilities at the lattice points, then bilinear between them.
    std::vector<float> sun(l * l), sky(l * l), tangents(a);
    for (std::size_t p = 0; p < l * l; ++p) {
        for (std::size_t k = 0; k < a; ++k) {
            tangents[k] = static_cast<float>(decodeHorizon(lattice.codes[p * a + k]));
        }
        sun[p] = static_cast<float>(sunVisibility(tangents, sunAzimuth, sunElevation, softness));
        sky[p] = static_cast<float>(skyVisibility(tangents));
    }
    const double scale = (lattice.size - 1.0) / (n - 1.0);
    for (int j = 0; j < n; ++j) {
        const double gy = j * scale;
        const auto y0 = std::min(static_cast<std::size_t>(gy), l - 2);
        const double fy = gy - static_cast<double>(y0);
        for (int i = 0; i < n; ++i) {
            const double gx = i * scale;
            const auto x0 = std::min(static_cast<std::size_t>(gx), l - 2);
            const double fx = gx - static_cast<double>(x0);
            auto bilinear = [&](const std::vector<float>& v) {
                const std::size_t p = y0 * l + x0;
                return (1.0 - fy) * ((1.0 - fx) * v[p] + fx * v[p + 1]) +
                       fy * ((1.0 - fx) * v[p + l] + fx * v[p + l + 1]);
            };
            const auto at = (static_cast<std::size_t>(j) * static_cast<std::size_t>(n) + static_cast<std::size_t>(i)) *
                                static_cast<std::size_t>(stride) +
                            static_cast<std::size_t>(offset);
            out[at] = static_cast<std::uint8_t>(std::lround(std::clamp(bilinear(sun), 0.0, 1.0) * 255.0));
            out[at + 1] = static_cast<std::uint8_t>(std::lround(std::clamp(bilinear(sky), 0.0, 1.0) * 255.0));
        }
    }
}

}  // namespace terrain
