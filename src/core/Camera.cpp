// Camera basis and matrices (see Camera.h for conventions).
#include "core/Camera.h"

#include "core/Check.h"

#include <glm/ext/matrix_clip_space.hpp>

#include <cmath>

namespace terrain {

glm::dvec3 Camera::forward() const
{
    double cp = std::cos(pitch);
    return {std::sin(yaw) * cp, std::cos(yaw) * cp, std::sin(pitch)};
}

glm::dvec3 Camera::right() const
{
    return {std::cos(yaw), -std::sin(yaw), 0.0};
}

glm::dvec3 Camera::up() const
{
    return glm::cross(right(), forward());
}

glm::dmat4 Camera::viewRotation() const
{
    // Rows of the rotation are the eye axes expressed in world space: x = right, y = up, z = -forward.
    glm::dvec3 r = right(), u = up(), b = -forward();
    glm::dmat4 m(1.0);
    m[0][0] = r.x, m[1][0] = r.y, m[2][0] = r.z;
    m[0][1] = u.x, m[1][1] = u.y, m[2][1] = u.z;
    m[0][2] = b.x, m[1][2] = b.y, m[2][2] = b.z;
    return m;
}

glm::dmat4 Camera::view() const
{
    glm::dmat4 m = viewRotation();
    glm::dvec3 t = -glm::dvec3(m * glm::dvec4(position, 0.0));
    m[3] = glm::dvec4(t, 1.0);
    return m;
}

void Camera::expectValid() const
{
    TERRAIN_EXPECTS(viewportWidth > 0 && viewportHeight > 0, "viewport must be at least 1x1 pixels");
    TERRAIN_EXPECTS(verticalFov > 0.0 && verticalFov < 3.14159, "vertical field of view must be in (0, pi)");
    TERRAIN_EXPECTS(nearPlane > 0.0 && farPlane > nearPlane, "need 0 < near < far");
}

glm::dmat4 Camera::projection() const
{
    expectValid();
    return glm::perspective(verticalFov, aspect(), nearPlane, farPlane);
}

glm::dmat4 Camera::viewProjection() const
{
    return projection() * view();
}

}  // namespace terrain
