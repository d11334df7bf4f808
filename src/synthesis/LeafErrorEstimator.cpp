// Paper 3.4.1, "Approximating Leaf Node Error": stochastic sampling of the detail added below a static leaf.
#include "synthesis/LeafErrorEstimator.h"

#include "core/Check.h"
#include "core/SplitMix64.h"
#include "quadtree/TemplateTriangulation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

namespace terrain {

namespace {

/// The leaf's surface (base + displacement) with (0, 0) at its south-west sample, in leaf sample units.
class LeafSurface {
public:
    LeafSurface(const DualHeightMap& leaf, int chunkSize) : mN(chunkSize), mW(leaf.size), mHeights(leaf.base.size())
    {
        for (std::size_t k = 0; k < mHeights.size(); ++k) {
            mHeights[k] = static_cast<double>(leaf.height(k));
        }
    }

    /// Height at (x, y) in [0, N - 1]^2, interpolated along the template triangles.
    double at(double x, double y) const
    {
        const int cx = std::min(static_cast<int>(x), mN - 2);
        const int cy = std::min(static_cast<int>(y), mN - 2);
        const double* row0 = mHeights.data() + static_cast<std::size_t>(cy + kBorder) * mW + cx + kBorder;
        const double* row1 = row0 + mW;
        return interpolateQuad(row0[0], row0[1], row1[0], row1[1], x - cx, y - cy);
    }

private:
    int mN;
    int mW;
    std::vector<double> mHeights;  ///< W x W
};

/// Largest |node - leaf| over the node's N x N samples; node sample (i, j) lies at leaf position
/// (x0 + i * step, y0 + j * step). Positions are dyadic fractions: exact in double.
double deviation(const LeafSurface& leaf, const DualHeightMap& node, int chunkSize, double x0, double y0, double step)
{
    const int w = node.size;
    double worst = 0.0;
    for (int j = 0; j < chunkSize; ++j) {
        const double y = y0 + j * step;
        const std::size_t row = static_cast<std::size_t>(j + kBorder) * w + kBorder;
        for (int i = 0; i < chunkSize; ++i) {
            const double d = std::abs(static_cast<double>(node.height(row + i)) - leaf.at(x0 + i * step, y));
            worst = std::max(worst, d);
        }
    }
    return worst;
}

}  // namespace

float estimateLeafDetailError(DualHeightMap leaf, const WindowPlacement& where, const DetailSynthesizer& synthesizer,
                              std::uint64_t seed, const LeafErrorSampling& sampling)
{
    const int n = synthesizer.chunkSize();
    const int w = synthesizer.windowSize();
    TERRAIN_EXPECTS(leaf.size == w && leaf.base.size() == static_cast<std::size_t>(w) * w,
                    "the leaf's window does not match the synthesizer's chunk size");
    TERRAIN_EXPECTS(sampling.descents >= 1 && sampling.descents <= 4, "descents must be 1..4");
    TERRAIN_EXPECTS(sampling.depth >= 1, "depth must be >= 1");
    // The runtime displaces a static leaf from its static parent's displacement; here it has no parent, so
    // its even samples are evaluated at its own spacing. Only their material weights can differ (slope at a
    // finer spacing), and only where materials blend: the same surface up to that blend.
    synthesizer.displace(where, nullptr, 0, leaf, ShownWeights::Skip);
    const LeafSurface surface(leaf, n);

    SplitMix64 random(seed);
    std::array<int, 4> children = {0, 1, 2, 3};
    for (int k = 3; k > 0; --k) {  // Fisher-Yates: the descents go through distinct children
        std::swap(children[static_cast<std::size_t>(k)], children[static_cast<std::size_t>(random.below(k + 1))]);
    }
    const double half = (n - 1) / 2.0;
    double worst = 0.0;
    for (int d = 0; d < sampling.descents; ++d) {
        int quadrant = children[static_cast<std::size_t>(d)];
        WindowPlacement place = childPlacement(where, quadrant, n);
        DualHeightMap node = synthesizer.synthesizeChild(leaf, quadrant, place, ShownWeights::Skip);
        // The node's south-west sample in leaf sample units, and its spacing in them.
        double x0 = (quadrant & 1) * half, y0 = (quadrant >> 1) * half, step = 0.5;
        for (int level = 1;; ++level) {
            worst = std::max(worst, deviation(surface, node, n, x0, y0, step));
            if (level == sampling.depth) {
                break;
            }
            quadrant = random.below(4);
            x0 += (quadrant & 1) * half * step;
            y0 += (quadrant >> 1) * half * step;
            step *= 0.5;
            place = childPlacement(place, quadrant, n);
            node = synthesizer.synthesizeChild(node, quadrant, place, ShownWeights::Skip);
        }
    }
    return static_cast<float>(worst);
}

}  // namespace terrain
