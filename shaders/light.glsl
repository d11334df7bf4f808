// The terrain's light and air. Shared by the quadtree's and the clipmap's fragment programs (terrain.frag,
// clipmap.frag) and the quadtree's vertex programs (their sun, for the air per vertex: surface.glsl,
// atmosphere.glsl's airAt); the sky (sky.frag) takes the same sun. The renderers set these from SceneStyle.
// With ATMOSPHERE (atmosphere = true): the node colours as reflectances lit by the sun through the air
// (sunTransmittance), by the sky's irradiance and by the light the ground around bounces onto slopes, seen
// through the air (aerialPerspective), tone mapped (atmosphere.glsl, included before this file). Without: the sun
// and an ambient light, and exponential haze with distance.

uniform vec3 uSunDirection;  // unit, towards the sun
uniform vec3 uSunColour;
uniform vec3 uAmbient;
uniform vec3 uHazeColour;
uniform float uHazeDistance;  // metres at which haze reaches 63 %
#ifdef ATMOSPHERE
// The mean reflectance of the ground around a point, for the light it bounces onto slopes (light/Atmosphere.h).
const float kGroundAlbedo = GROUND_ALBEDO;

// The surface colour `albedo` lit with unit normal n through `air`. `visibility`: the share of the sun (x) and of the
// sky (y) that the terrain around does not hide (1, 1 in the open); the sky's also scales the light the ground
// around bounces (what hides the sky hides the ground around too).
vec3 litThroughAir(vec3 albedo, vec3 n, vec2 visibility, Air air)
{
    vec3 reflectance = albedo * albedo;  // the display's gamma 2 (toneMap) undone
    vec3 sunlight = air.sunlight;
    vec3 sky = air.skylight;
    // What the ground around receives, reflected back to a tilted surface from below its horizon: the
    // surroundings taken as a lit flat ground of reflectance kGroundAlbedo, seen over (1 - n.z) / 2 of the sphere.
    vec3 ground = kGroundAlbedo * (sunlight * max(uSunDirection.z, 0.0) + sky);
    vec3 irradiance = visibility.x * sunlight * max(dot(n, uSunDirection), 0.0) +
                      visibility.y * (sky * (0.5 + 0.5 * n.z) + ground * (0.5 - 0.5 * n.z));
    return toneMap(reflectance / kPi * irradiance * air.transmittance + air.inscattered);
}
#endif

// The surface colour `albedo` lit with unit normal n, seen through the air from `relative` metres away, with the
// terrain's `visibility` (litThroughAir) or, without ATMOSPHERE, hazed.
vec3 litAndHazed(vec3 albedo, vec3 n, vec3 relative, vec2 visibility)
{
#ifdef ATMOSPHERE
    return litThroughAir(albedo, n, visibility, airAt(relative, uSunDirection));
#else
    vec3 light = visibility.y * uAmbient * (0.6 + 0.4 * n.z) + visibility.x * uSunColour * max(dot(n, uSunDirection), 0.0);
    vec3 colour = albedo * light;
    float haze = 1.0 - exp(-length(relative) / uHazeDistance);
    return mix(colour, uHazeColour, haze);
#endif
}
