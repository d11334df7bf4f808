// The viewer's camera on the CPU, in double precision (docs/design.md, "World space"): world metres,
// x east, y north, z up. Orientation is yaw/pitch, no roll: yaw 0 looks north (+y), positive yaw turns
// east (clockwise seen from above); pitch 0 is horizontal, positive looks up.
#pragma once

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

namespace terrain {

/// Angles: radians in one degree, and degrees in one radian.
inline constexpr double kRadiansPerDegree = 3.14159265358979323846 / 180.0;
inline constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;

struct Camera {
    glm::dvec3 position{0.0};                 ///< metres, world space
    double yaw = 0.0;                         ///< radians, any value (wraps)
    double pitch = 0.0;                       ///< radians, in [-pi/2, pi/2]
    double verticalFov = 1.0471975511965976;  ///< radians, in (0, pi); default 60 degrees
    int viewportWidth = 1280;                 ///< pixels, > 0
    int viewportHeight = 720;                 ///< pixels, > 0 (S of eq. 3.2)
    double nearPlane = 0.5;                   ///< metres, > 0
    double farPlane = 100000.0;               ///< metres, > nearPlane

    double aspect() const { return static_cast<double>(viewportWidth) / static_cast<double>(viewportHeight); }

    /// Unit view direction: (sin yaw cos pitch, cos yaw cos pitch, sin pitch).
    glm::dvec3 forward() const;
    /// Unit vector to the right of the view, always horizontal: (cos yaw, -sin yaw, 0).
    glm::dvec3 right() const;
    /// Unit vector up in the image: cross(right, forward).
    glm::dvec3 up() const;

    /// World -> eye transform in OpenGL's convention (eye looks down -z, y up in the image).
    /// Translates by -position: for large worlds prefer viewRotation() with camera-relative positions.
    glm::dmat4 view() const;
    /// view() without the translation: camera-relative world positions -> eye space.
    glm::dmat4 viewRotation() const;
    /// Checks the ranges documented above (a caller's bug when broken: aborts with a message).
    void expectValid() const;

    /// OpenGL perspective projection (clip z in [-w, w]) from verticalFov, aspect, near and far.
    glm::dmat4 projection() const;
    /// projection() * view().
    glm::dmat4 viewProjection() const;
};

}  // namespace terrain
