#include "heightfield/Roughness.h"

#include "core/Check.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace terrain {

double RoughnessLaw::at(double samples) const
{
    TERRAIN_EXPECTS(samples > 0.0, "a lag must be > 0");
    return amplitude * std::pow(samples, exponent);
}

double MidpointSums::rms() const
{
    return count == 0 ? 0.0 : std::sqrt(squares / static_cast<double>(count));
}

MidpointSums midpointDeviation(std::span<const float> heights, int width, int height, int lag, int x0, int y0, int x1,
                               int y1, double metresPerUnit)
{
    TERRAIN_EXPECTS(lag >= 1, "the lag must be >= 1 sample");
    TERRAIN_EXPECTS(width >= 1 && height >= 1 && heights.size() == static_cast<std::size_t>(width) * height,
                    "heights must hold width x height samples");
    TERRAIN_EXPECTS(0 <= x0 && x0 <= x1 && x1 <= width && 0 <= y0 && y0 <= y1 && y1 <= height,
                    "the region must lie inside the grid");
    auto h = [&](int i, int j) -> double { return heights[static_cast<std::size_t>(j) * width + i]; };
    MidpointSums sums;
    auto add = [&](double a, double m, double b) {
        const double d = (m - 0.5 * (a + b)) * metresPerUnit;
        if (std::isfinite(d)) {
            sums.squares += d * d;
            ++sums.count;
        }
    };
    for (int j = y0; j < y1; ++j) {
        for (int i = std::max(x0, lag); i < std::min(x1, width - lag); ++i) {
            add(h(i - lag, j), h(i, j), h(i + lag, j));
        }
    }
    for (int j = std::max(y0, lag); j < std::min(y1, height - lag); ++j) {
        for (int i = x0; i < x1; ++i) {
            add(h(i, j - lag), h(i, j), h(i, j + lag));
        }
    }
    return sums;
}

RoughnessLaw fitRoughnessLaw(std::span<const double> rms)
{
    TERRAIN_EXPECTS(rms.size() == kRoughnessLags.size(), "one RMS per lag of kRoughnessLags");
    std::vector<double> lx, ly, wt;
    for (std::size_t k = 0; k < rms.size(); ++k) {
        if (rms[k] > 0.0 && std::isfinite(rms[k])) {
            lx.push_back(std::log(static_cast<double>(kRoughnessLags[k])));
            ly.push_back(std::log(rms[k]));
            wt.push_back(kRoughnessLagWeights[k]);
        }
    }
    RoughnessLaw law;
    if (lx.empty()) {
        law.amplitude = 0.0;
        law.exponent = 0.5 * (kMinRoughnessExponent + kMaxRoughnessExponent);
        return law;
    }
    double n = 0.0;
    for (double w : wt) {
        n += w;
    }
    double mx = 0.0, my = 0.0;
    for (std::size_t k = 0; k < lx.size(); ++k) {
        mx += wt[k] * lx[k] / n;
        my += wt[k] * ly[k] / n;
    }
    double sxx = 0.0, sxy = 0.0;
    for (std::size_t k = 0; k < lx.size(); ++k) {
        sxx += wt[k] * (lx[k] - mx) * (lx[k] - mx);
        sxy += wt[k] * (lx[k] - mx) * (ly[k] - my);
    }
    const double slope = sxx > 0.0 ? sxy / sxx : 0.5 * (kMinRoughnessExponent + kMaxRoughnessExponent);
    law.exponent = std::clamp(slope, kMinRoughnessExponent, kMaxRoughnessExponent);
    // log A = weighted mean of (log D - H log r): the weighted geometric mean of D(r) / r^H.
    law.amplitude = std::exp(my - law.exponent * mx);
    return law;
}

}  // namespace terrain
