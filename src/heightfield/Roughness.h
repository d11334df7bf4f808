// How a terrain's roughness scales with distance, measured from its own samples, so detail
// synthesis can continue that law below the data's spacing.
//
// The measure is slope-free: the midpoint deviation d(x, r) = h(x) - (h(x - r) + h(x + r)) / 2 along
// east-west and north-south lines (a plane gives 0), and its RMS D(r) over a region. For fractal terrain
// D(r) follows a power law D(r) = A (r / s)^H over a range of lags (s the sample spacing; H the Hurst
// exponent, the slope of the structure function's log-log plot halved), which fitRoughnessLaw finds from the
// lags kRoughnessLags.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

namespace terrain {

/// The lags, in samples, of a roughness measurement: the finest octaves of the data.
inline constexpr std::array<int, 4> kRoughnessLags = {1, 2, 4, 8};
/// Their weights in the fit: the finest lags count most, since the law is continued below them. Measured
/// on the ground truth (RoughnessGroundTruthTest: 90 m SRTM decimated 4x and 16x, real / synthesized D at 90
/// to 720 m): equal weights 0.63 .. 1.26 on the bundled terrain but 0.27 .. 0.98 on the Jacksboro DEM,
/// whose ridges have a characteristic spacing; lags 1 and 2 alone 0.83 .. 1.42 and 0.30 .. 1.02.
inline constexpr std::array<double, 4> kRoughnessLagWeights = {1.0, 1.0, 0.25, 0.0625};
/// The exponents a fit may give. Below 0.1 the law is noise without structure; above 1 the surface is
/// smoother than any fractal (a curve's D(r) grows as r^2), and continuing it would add nearly nothing.
inline constexpr double kMinRoughnessExponent = 0.1;
inline constexpr double kMaxRoughnessExponent = 1.0;

/// D(r) = amplitude (r / s)^exponent, r and s in metres, s the spacing of the samples it was measured on.
struct RoughnessLaw {
    double amplitude = 0.0;  ///< metres: RMS midpoint deviation at a lag of one sample spacing
    double exponent = 0.5;   ///< H, in [kMinRoughnessExponent, kMaxRoughnessExponent]

    /// D at a lag of `samples` sample spacings (any > 0, also below 1).
    double at(double samples) const;
    bool operator==(const RoughnessLaw&) const = default;
};

/// Sums of d(x, r)^2 over a region: adding up regions gives the RMS of their union.
struct MidpointSums {
    double squares = 0.0;
    std::uint64_t count = 0;

    double rms() const;
    MidpointSums& operator+=(const MidpointSums& other)
    {
        squares += other.squares;
        count += other.count;
        return *this;
    }
};

/// The sums of d(x, r)^2, in metres (heights x `metresPerUnit`), over the samples x of the rectangle
/// [x0, x1) x [y0, y1) of the `width` x `height` grid `heights` (row-major, index j * width + i), along rows
/// and along columns, where x - r and x + r lie on the grid. Non-finite samples (no data) are skipped with
/// every deviation they take part in. Preconditions: lag >= 1, the rectangle inside the grid, heights holds
/// width * height values.
MidpointSums midpointDeviation(std::span<const float> heights, int width, int height, int lag, int x0, int y0, int x1,
                               int y1, double metresPerUnit = 1.0);

/// The law through D at kRoughnessLags (`rms[k]` at lag kRoughnessLags[k]): least squares of log D against
/// log r weighted by kRoughnessLagWeights, the exponent clamped to [kMinRoughnessExponent, kMaxRoughnessExponent] and
/// the amplitude then refitted (the weighted geometric mean of D(r) / r^H). Lags without deviations (D = 0 or no
/// samples) are left out; with none left the amplitude is 0, and with one the exponent is the middle of the range.
RoughnessLaw fitRoughnessLaw(std::span<const double> rms);

}  // namespace terrain
