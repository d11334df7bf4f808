// Axis-aligned boxes in world space (metres, double precision): the nested node bounding boxes of
// paper 3.2.12 and the distance used by the error test of eq. 3.3.
#pragma once

#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>

namespace terrain {

/// A closed box [lo, hi] per axis. Valid when lo <= hi on every axis (a point box is valid).
struct Aabb {
    glm::dvec3 lo{0.0};
    glm::dvec3 hi{0.0};

    bool contains(const glm::dvec3& p) const
    {
        return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z;
    }
};

/// Euclidean distance (metres) from point `p` to the closest point of `box`; 0 when `p` is inside.
inline double distanceToAabb(const glm::dvec3& p, const Aabb& box)
{
    double dx = std::max({box.lo.x - p.x, 0.0, p.x - box.hi.x});
    double dy = std::max({box.lo.y - p.y, 0.0, p.y - box.hi.y});
    double dz = std::max({box.lo.z - p.z, 0.0, p.z - box.hi.z});
    return std::sqrt(dx * dx + dy * dy + dz * dz);
}

}  // namespace terrain
