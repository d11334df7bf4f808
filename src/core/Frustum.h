// View frustum as six planes, and the conservative box test used for hierarchical culling (paper 3.2.12).
#pragma once

#include "core/Aabb.h"
#include "core/Camera.h"

#include <array>

namespace terrain {

/// A plane n . p + d = 0; the frustum's inside is where n . p + d >= 0. `normal` is unit length.
struct Plane {
    glm::dvec3 normal{0.0, 0.0, 1.0};
    double d = 0.0;

    double signedDistance(const glm::dvec3& p) const { return glm::dot(normal, p) + d; }
};

class Frustum {
public:
    enum Side { kLeft, kRight, kBottom, kTop, kNear, kFar };

    /// The frustum of `camera` in world space (metres), the same volume as camera.viewProjection() clips.
    /// Built from the camera's basis rather than from the matrix so that planes stay exact far from the
    /// origin.
    static Frustum fromCamera(const Camera& camera);

    const std::array<Plane, 6>& planes() const { return mPlanes; }

    /// True when `p` is inside or on the boundary.
    bool contains(const glm::dvec3& p) const;

    /// Conservative box test: false only when `box` lies entirely outside one plane, so a box that
    /// intersects the frustum is never rejected (a box near a corner outside the frustum may be accepted).
    /// Monotone: if a box is rejected, every box inside it is rejected too.
    bool intersects(const Aabb& box) const;

private:
    std::array<Plane, 6> mPlanes{};
};

}  // namespace terrain
