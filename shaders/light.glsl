// The terrain's light and air. Shared by the quadtree's and the clipmap's fragment programs (terrain.frag,
// clipmap.frag); the sky (sky.frag) takes the same sun. The renderers set these from SceneStyle.
// With ATMOSPHERE (atmosphere = true): the node colours as reflectances lit by the sun through the air
// (sunTransmittance) and by the sky's irradiance, seen through the air (aerialPerspective), tone mapped
// (atmosphere.glsl, included before this file). Without: the sun and an ambient light, and exponential haze with distance.

uniform vec3 uSunDirection;  // unit, towards the sun
uniform vec3 uSunColour;
uniform vec3 uAmbient;
uniform vec3 uHazeColour;
uniform float uHazeDistance;  // metres at which haze reaches 63 %

// The surface colour `albedo` lit with unit normal n, seen through the air from `relative` metres away.
vec3 litAndHazed(vec3 albedo, vec3 n, vec3 relative)
{
#ifdef ATMOSPHERE
    vec3 reflectance = pow(albedo, vec3(2.2));
    float altitude = uCameraAltitude + relative.z;
    vec3 sunlight = sunTransmittance(altitude);
    vec3 irradiance = sunlight * max(dot(n, uSunDirection), 0.0) + skyIrradiance(sunlight, uSunDirection) * (0.5 + 0.5 * n.z);
    return toneMap(aerialPerspective(reflectance / kPi * irradiance, relative, uSunDirection));
#else
    vec3 light = uAmbient * (0.6 + 0.4 * n.z) + uSunColour * max(dot(n, uSunDirection), 0.0);
    vec3 colour = albedo * light;
    float haze = 1.0 - exp(-length(relative) / uHazeDistance);
    return mix(colour, uHazeColour, haze);
#endif
}
