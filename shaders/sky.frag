#version 330 core
// The sky. With ATMOSPHERE (atmosphere = true): the air's in-scattered light along the view ray and the sun's
// disc through the air, tone mapped (atmosphere.glsl). Without: a gradient from the haze colour at and below the
// horizon to a deeper blue at the zenith, and a soft sun.
in vec3 vDirection;

uniform vec3 uHazeColour;
uniform vec3 uZenithColour;
uniform vec3 uSunDirection;
uniform vec3 uSunColour;

out vec4 fragColour;

#include "atmosphere.glsl"

// The sun's angular radius, radians.
const float kSunRadius = 0.00465;

void main()
{
    vec3 direction = normalize(vDirection);
#ifdef ATMOSPHERE
    vec3 radiance = skyRadiance(direction, uSunDirection);
    // The disc: the sun's irradiance (1 above the air) spread over its solid angle, dimmed by the air.
    float angle = acos(clamp(dot(direction, uSunDirection), -1.0, 1.0));
    float disc = 1.0 - smoothstep(0.8 * kSunRadius, kSunRadius, angle);
    radiance += disc * sunTransmittance(uCameraAltitude) / (kPi * kSunRadius * kSunRadius);
    fragColour = vec4(toneMap(radiance), 1.0);
#else
    float elevation = max(direction.z, 0.0);
    vec3 colour = mix(uHazeColour, uZenithColour, pow(elevation, 0.6));
    float sun = max(dot(direction, uSunDirection), 0.0);
    colour += uSunColour * (pow(sun, 600.0) * 2.0 + pow(sun, 12.0) * 0.15);
    fragColour = vec4(colour, 1.0);
#endif
}
