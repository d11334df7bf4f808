// The terrain's light and air: the sun and the sky's ambient light on a surface, and haze with distance. Shared by
// the quadtree's and the clipmap's fragment programs (terrain.frag, clipmap.frag); the sky (sky.frag) takes the same
// sun and haze colour. The renderers set these from SceneStyle.

uniform vec3 uSunDirection;   // unit, towards the sun
uniform vec3 uSunColour;
uniform vec3 uAmbient;
uniform vec3 uHazeColour;
uniform float uHazeDistance;  // metres at which haze reaches 63 %

// The surface colour `albedo` lit with unit normal n, seen through the haze from `relative` metres away.
vec3 litAndHazed(vec3 albedo, vec3 n, vec3 relative)
{
    vec3 light = uAmbient * (0.6 + 0.4 * n.z) + uSunColour * max(dot(n, uSunDirection), 0.0);
    vec3 colour = albedo * light;
    float haze = 1.0 - exp(-length(relative) / uHazeDistance);
    return mix(colour, uHazeColour, haze);
}
