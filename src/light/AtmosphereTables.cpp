// The air's tables on the CPU, the reference of the renderer's (AtmosphereTables.h).
#include "light/AtmosphereTables.h"

#include "core/Check.h"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>

namespace terrain {

namespace {

/// The sun's azimuth (atan2(y, x)); 0 for a sun at the zenith or nadir.
double azimuthOf(const glm::dvec3& v)
{
    return v.x == 0.0 && v.y == 0.0 ? 0.0 : std::atan2(v.y, v.x);
}

/// Cell i and the weight of cell i + 1 of coordinate c in [0, 1] over n cells on the grid points.
std::pair<int, double> cellOf(double c, int n)
{
    const double x = std::clamp(c, 0.0, 1.0) * (n - 1);
    const int i = std::min(static_cast<int>(x), n - 2);
    return {i, x - i};
}

}  // namespace

glm::dvec2 directionCoordinate(const glm::dvec3& view, const glm::dvec3& sun)
{
    // tan(azimuth / 4) from the two horizontal unit directions a and b: |a - b| / (2 + |a + b|), the sine and the
    // cosine of half the azimuth over 1 + that cosine; 0 where either direction is vertical.
    const double viewHorizontal = std::hypot(view.x, view.y), sunHorizontal = std::hypot(sun.x, sun.y);
    double azimuthTangent = 0.0;
    if (viewHorizontal > 0.0 && sunHorizontal > 0.0) {
        const glm::dvec2 a = glm::dvec2(view.x, view.y) / viewHorizontal, b = glm::dvec2(sun.x, sun.y) / sunHorizontal;
        azimuthTangent = glm::length(a - b) / (2.0 + glm::length(a + b));
    }
    // tan(|elevation| / 2): |z| over the length plus the horizontal length.
    const double length = std::hypot(viewHorizontal, view.z);
    const double elevationTangent = length > 0.0 ? std::abs(view.z) / (length + viewHorizontal) : 0.0;
    return {std::sqrt(std::min(azimuthTangent, 1.0)),
            0.5 + 0.5 * std::copysign(std::sqrt(std::min(elevationTangent, 1.0)), view.z)};
}

glm::dvec3 directionAt(const glm::dvec2& coordinate, const glm::dvec3& sun)
{
    const double azimuth = azimuthOf(sun) - 4.0 * std::atan(std::clamp(coordinate.x * coordinate.x, 0.0, 1.0));
    const double e = 2.0 * coordinate.y - 1.0;
    const double t = std::min(e * e, 1.0);  // tan(|elevation| / 2)
    const double horizontal = (1.0 - t * t) / (1.0 + t * t);
    const double z = std::copysign(2.0 * t / (1.0 + t * t), e);
    return {horizontal * std::cos(azimuth), horizontal * std::sin(azimuth), z};
}

double distanceCoordinate(double distance, double range)
{
    TERRAIN_EXPECTS(range > 0.0, "a table range > 0");
    return std::sqrt(std::clamp(distance / range, 0.0, 1.0));
}

double distanceAt(double coordinate, double range)
{
    return range * coordinate * coordinate;
}

double aerialTableRange(const Camera& camera)
{
    const double up = std::tan(camera.verticalFov / 2.0);
    const double right = up * camera.aspect();
    return camera.farPlane * std::sqrt(1.0 + up * up + right * right);
}

TableAltitudes tableAltitudes(double altitude, const AtmosphereModel& air)
{
    const double step = kTableAltitudeShare * std::min(air.rayleighHeight, air.mieHeight);
    if (!std::isfinite(altitude) || !(step > 0.0) || !std::isfinite(step)) {
        return {altitude, altitude, 0.0};
    }
    const double lower = std::floor(altitude / step) * step, upper = lower + step;
    if (!std::isfinite(lower) || !(upper > lower) || !(lower <= altitude && altitude <= upper)) {
        return {altitude, altitude, 0.0};  // beyond what a double tells apart at that step
    }
    return {lower, upper, std::clamp((altitude - lower) / (upper - lower), 0.0, 1.0)};
}

AtmosphereTables::AtmosphereTables(const AtmosphereModel& air, double altitude, const glm::dvec3& sun, double range,
                                   const MultipleScattering* multiple)
    : mSun(sun), mRange(range)
{
    TERRAIN_EXPECTS(range > 0.0, "a table range > 0");
    mAerial.reserve(static_cast<std::size_t>(kAerialTableAzimuths) * kAerialTableElevations * kAerialTableDistances);
    for (int d = 0; d < kAerialTableDistances; ++d) {
        // The first cell holds the limit at distance 0: a segment a millionth of the range.
        const double w = std::max(d / (kAerialTableDistances - 1.0), 1e-3);
        const double distance = distanceAt(w, range);
        for (int e = 0; e < kAerialTableElevations; ++e) {
            for (int a = 0; a < kAerialTableAzimuths; ++a) {
                const glm::dvec3 view =
                    directionAt({a / (kAerialTableAzimuths - 1.0), e / (kAerialTableElevations - 1.0)}, sun);
                mAerial.push_back(
                    aerialPerspective(air, altitude, view * distance, sun, kAerialSamples, multiple).inscattered /
                    (w * w));
            }
        }
    }
    mSky.reserve(static_cast<std::size_t>(kSkyTableAzimuths) * kSkyTableElevations);
    for (int e = 0; e < kSkyTableElevations; ++e) {
        for (int a = 0; a < kSkyTableAzimuths; ++a) {
            const glm::dvec3 view = directionAt({a / (kSkyTableAzimuths - 1.0), e / (kSkyTableElevations - 1.0)}, sun);
            mSky.push_back(skyRadiance(air, altitude, view, sun, kSkySamples, multiple));
        }
    }
}

glm::dvec3 AtmosphereTables::aerialCell(int azimuth, int elevation, int distance) const
{
    return mAerial[(static_cast<std::size_t>(distance) * kAerialTableElevations + elevation) * kAerialTableAzimuths +
                   azimuth];
}

glm::dvec3 AtmosphereTables::skyCell(int azimuth, int elevation) const
{
    return mSky[static_cast<std::size_t>(elevation) * kSkyTableAzimuths + azimuth];
}

glm::dvec3 AtmosphereTables::inscattered(const glm::dvec3& view, double distance) const
{
    const glm::dvec2 c = directionCoordinate(view, mSun);
    const auto [a, wa] = cellOf(c.x, kAerialTableAzimuths);
    const auto [e, we] = cellOf(c.y, kAerialTableElevations);
    const double w = distanceCoordinate(distance, mRange);
    const auto [d, wd] = cellOf(w, kAerialTableDistances);
    glm::dvec3 sum(0.0);
    for (int k = 0; k < 8; ++k) {
        const int da = k & 1, de = (k >> 1) & 1, dd = k >> 2;
        sum += (da ? wa : 1.0 - wa) * (de ? we : 1.0 - we) * (dd ? wd : 1.0 - wd) * aerialCell(a + da, e + de, d + dd);
    }
    return sum * (w * w);
}

glm::dvec3 AtmosphereTables::sky(const glm::dvec3& view) const
{
    const glm::dvec2 c = directionCoordinate(view, mSun);
    const auto [a, wa] = cellOf(c.x, kSkyTableAzimuths);
    const auto [e, we] = cellOf(c.y, kSkyTableElevations);
    return (1.0 - we) * ((1.0 - wa) * skyCell(a, e) + wa * skyCell(a + 1, e)) +
           we * ((1.0 - wa) * skyCell(a, e + 1) + wa * skyCell(a + 1, e + 1));
}

}  // namespace terrain
