// The triangulation every chunk uses (3.2.9 template mesh): each grid quad with corners (i, j) and
// (i + 1, j + 1) is split along its south-west to north-east diagonal. Simplification errors (3.2.5),
// height queries and the morph targets of the renderer (eq. 3.4) all interpolate along these triangles,
// so they must agree on this one choice.
#pragma once

namespace terrain {

/// Height of the triangulated surface inside the unit quad with corner heights h00 (south-west),
/// h10 (south-east), h01 (north-west), h11 (north-east), at fractional position (fx, fy) in [0, 1]^2.
inline double interpolateQuad(double h00, double h10, double h01, double h11, double fx, double fy)
{
    // Lower-right triangle (fx >= fy): corners 00, 10, 11. Upper-left (fx < fy): 00, 01, 11.
    if (fx >= fy) {
        return h00 + fx * (h10 - h00) + fy * (h11 - h10);
    }
    return h00 + fy * (h01 - h00) + fx * (h11 - h01);
}

}  // namespace terrain
