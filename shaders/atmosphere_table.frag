#version 330 core
// Fills one cell of the frame's air tables a fragment (render/AtmosphereTextures.h; layout and reference in
// light/AtmosphereTables.h). With SKY_TABLE: the sky's radiance at the cell's direction. Without: one distance
// slice of the aerial table, the in-scattered light of the segment to the slice's distance along the cell's
// direction, divided by (distance / range) so that it is smooth down to distance 0 (the first slice holds that
// limit, taken at a millionth of the range). With BLEND_TABLES: the cell of the same table, uWeight of the way
// between two tables filled at the altitudes around the viewer's (render/AtmosphereTextures.h, tableAltitudes).
#define ATMOSPHERE_TABLE
#include "atmosphere.glsl"

#ifdef BLEND_TABLES
#ifdef SKY_TABLE
uniform sampler2D uLower;
uniform sampler2D uUpper;
#else
uniform sampler3D uLower;
uniform sampler3D uUpper;
#endif
uniform float uWeight;
#endif

uniform vec3 uSunDirection;  // unit, towards the sun
#ifndef SKY_TABLE
uniform int uSlice;          // the aerial table's distance slice being filled
uniform float uAerialRange;  // metres the aerial table spans
#endif

out vec4 fragColour;

void main()
{
    vec2 cell = floor(gl_FragCoord.xy);
#if defined(BLEND_TABLES) && defined(SKY_TABLE)
    fragColour = mix(texelFetch(uLower, ivec2(cell), 0), texelFetch(uUpper, ivec2(cell), 0), uWeight);
#elif defined(BLEND_TABLES)
    fragColour = mix(texelFetch(uLower, ivec3(cell, uSlice), 0), texelFetch(uUpper, ivec3(cell, uSlice), 0), uWeight);
#elif defined(SKY_TABLE)
    vec3 view = tableDirection(cell / vec2(SKY_TABLE_AZIMUTHS - 1, SKY_TABLE_ELEVATIONS - 1), uSunDirection);
    fragColour = vec4(skySum(view, uSunDirection), 1.0);
#else
    vec3 view = tableDirection(cell / vec2(AERIAL_TABLE_AZIMUTHS - 1, AERIAL_TABLE_ELEVATIONS - 1), uSunDirection);
    float w = max(float(uSlice) / float(AERIAL_TABLE_DISTANCES - 1), 1e-3);
    fragColour = vec4(aerialSum(view, uAerialRange * w * w, uSunDirection) / (w * w), 1.0);
#endif
}
