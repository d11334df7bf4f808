// The dual height field of a node (paper 4.2.4, the paper's DualHeightMap): a base height field (read from
// the map for static nodes, subdivided from the parent's base for dynamic ones) and a displacement height
// field (the material's fractal), kept apart so that children subdivide the smooth base and add their own
// displacement, and summed only where the surface is needed (rendering, bounds, queries).
#pragma once

#include "core/Check.h"

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace terrain {

struct DualHeightMap {
    int size = 0;                     ///< W: samples per side of the window (N + 4, border included)
    std::vector<float> base;          ///< W x W metres above the map's height offset, rows south to north
    std::vector<float> displacement;  ///< W x W metres, or empty: no displacement anywhere
    /// W x W placement slopes in degrees, where several materials blend by slope (DetailSynthesizer::displace),
    /// else empty.
    std::vector<float> slope;
    /// W x W placement curvatures in degrees (placementCurvature), nested like the slopes, where a material
    /// is placed by curvature, else empty (0 everywhere).
    std::vector<float> curvature;
    /// W x W x 4 material weights (round(255 w), material m at byte m) the ground shows at the samples (blended
    /// by the materials' heights, MaterialSet::weights; the displacement's own are not kept), where several
    /// materials are placed, else empty.
    std::vector<std::uint8_t> weights;

    bool hasDisplacement() const { return !displacement.empty(); }
    /// The surface height of window sample k = j * W + i: base + displacement (3.3.1).
    float height(std::size_t k) const { return displacement.empty() ? base[k] : base[k] + displacement[k]; }
    /// All W x W surface heights into `out` (W * W values).
    void surface(std::span<float> out) const
    {
        TERRAIN_EXPECTS(out.size() >= base.size(), "out must hold W * W heights");
        for (std::size_t k = 0; k < base.size(); ++k) {
            out[k] = height(k);
        }
    }
};

}  // namespace terrain
