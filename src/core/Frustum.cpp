// Frustum planes from a camera's basis and the "positive vertex" box test (paper 3.2.12).
#include "core/Frustum.h"

#include <cmath>

namespace terrain {

Frustum Frustum::fromCamera(const Camera& camera)
{
    // Side planes pass through the camera position. A side plane's inward normal is a combination of
    // forward and the side axis: e.g. left = normalize(cos(h) * right + sin(h) * forward) with h the
    // horizontal half-angle.
    camera.expectValid();
    glm::dvec3 f = camera.forward(), r = camera.right(), u = camera.up();
    double tanV = std::tan(camera.verticalFov * 0.5);
    double tanH = tanV * camera.aspect();
    auto through = [&](glm::dvec3 n) {
        n = glm::normalize(n);
        return Plane{n, -glm::dot(n, camera.position)};
    };
    Frustum fr;
    fr.mPlanes[kLeft] = through(r + tanH * f);
    fr.mPlanes[kRight] = through(-r + tanH * f);
    fr.mPlanes[kBottom] = through(u + tanV * f);
    fr.mPlanes[kTop] = through(-u + tanV * f);
    fr.mPlanes[kNear] = Plane{f, -glm::dot(f, camera.position) - camera.nearPlane};
    fr.mPlanes[kFar] = Plane{-f, glm::dot(f, camera.position) + camera.farPlane};
    return fr;
}

bool Frustum::contains(const glm::dvec3& p) const
{
    for (const Plane& plane : mPlanes) {
        if (plane.signedDistance(p) < 0.0) {
            return false;
        }
    }
    return true;
}

bool Frustum::intersects(const Aabb& box) const
{
    for (const Plane& plane : mPlanes) {
        // The box corner furthest along the normal; if even it is outside, the whole box is.
        glm::dvec3 p{plane.normal.x >= 0.0 ? box.hi.x : box.lo.x, plane.normal.y >= 0.0 ? box.hi.y : box.lo.y,
                     plane.normal.z >= 0.0 ? box.hi.z : box.lo.z};
        if (plane.signedDistance(p) < 0.0) {
            return false;
        }
    }
    return true;
}

}  // namespace terrain
