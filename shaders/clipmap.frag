#version 330 core
// Geometry clipmap fragment program (render/ClipmapRenderer.h): the ring's colour blended with the coarser
// ring's by the vertex's transition weight (seed 002 blends textures in the transition region too), lit and
// hazed as shaders/terrain.frag lights the quadtree's nodes, with the materials' detail textures (DETAIL,
// shaders/detail.glsl) weighted by the ring's material weights, and with NORMAL_MAP by the rings' normal maps,
// both blended like the colours. Where a sample's morph is under way (shaders/clipmap.vert), each of them is on
// its way from what was drawn before (the uPrevious* layers) by the vertex's remaining fraction, in this ring and
// in the coarser one. Outside the input's samples: discarded.

in vec3 vRelative;
in vec3 vNormal;
in vec2 vFineUv;
in vec2 vCoarseUv;
in float vBlend;
in float vRemaining;        // of this ring's morph at the fragment (0: none under way)
in float vCoarseRemaining;  // of the coarser ring's
in float vSkyVisibility;    // the share of the sky the terrain around leaves the fragment (shaders/clipmap.vert)

uniform sampler2DArray uColour;          // per ring: n x n RGBA8, toroidal (REPEAT wraps it)
uniform sampler2DArray uPreviousColour;  // what they were drawn as when their morph started
uniform int uRing;
uniform int uHasCoarser;
uniform vec4 uValidRect;  // camera-relative x0, y0, x1, y1 of the input's samples
uniform int uWireframe;
#ifdef NORMAL_MAP
// The nodes' normal maps (synthesis/NormalMap.h) on the rings' texels: finer shading than the rings' triangles.
in vec2 vNormalUv;
in vec2 vCoarseNormalUv;
uniform sampler2DArray uNormals;  // per ring: (r n)^2 unit normals (x, y), toroidal
uniform sampler2DArray uPreviousNormals;
#endif
#ifdef DETAIL
in vec2 vLocal;
uniform sampler2DArray uMaterials;  // per ring: n x n RGBA8 material weights, toroidal
uniform sampler2DArray uPreviousMaterials;
uniform vec4 uLayerOrigin[LAYER_COUNT];  // the window origin in repeats (xy) and lattice coordinates (zw), reduced
#define LAYER_ORIGIN(k) uLayerOrigin[k]
#include "detail.glsl"
#endif
#include "atmosphere.glsl"
#include "light.glsl"

out vec4 fragColour;

// A layer's texel at `uv`, `remaining` of the way back to what it was drawn as when its morph started. The
// layers have no mipmaps: textureLod samples the same level inside the branch that most fragments skip.
vec4 morphed(sampler2DArray current, sampler2DArray previous, vec2 uv, int layer, float remaining)
{
    vec4 now = texture(current, vec3(uv, float(layer)));
    return remaining > 0.0 ? mix(now, textureLod(previous, vec3(uv, float(layer)), 0.0), remaining) : now;
}

void main()
{
    if (vRelative.x < uValidRect.x || vRelative.y < uValidRect.y || vRelative.x > uValidRect.z ||
        vRelative.y > uValidRect.w) {
        discard;
    }
    if (uWireframe != 0) {
        fragColour = vec4(0.05, 0.05, 0.05, 1.0);
        return;
    }
    // rgb the albedo, a the sun's visibility (lod/ClipmapTerrain.h: 1 without shadows).
    vec4 colour = morphed(uColour, uPreviousColour, vFineUv, uRing, vRemaining);
    if (uHasCoarser != 0) {
        colour = mix(colour, morphed(uColour, uPreviousColour, vCoarseUv, uRing + 1, vCoarseRemaining), vBlend);
    }
    vec3 albedo = colour.rgb;
#ifdef NORMAL_MAP
    vec2 nxy = morphed(uNormals, uPreviousNormals, vNormalUv, uRing, vRemaining).xy;
    if (uHasCoarser != 0) {
        nxy = mix(nxy, morphed(uNormals, uPreviousNormals, vCoarseNormalUv, uRing + 1, vCoarseRemaining).xy, vBlend);
    }
    vec3 n = normalize(vec3(nxy, sqrt(max(1.0 - dot(nxy, nxy), 0.0))));
#else
    vec3 n = normalize(vNormal);
#endif
#ifdef DETAIL
    vec4 materials = morphed(uMaterials, uPreviousMaterials, vFineUv, uRing, vRemaining);
    if (uHasCoarser != 0) {
        materials = mix(materials, morphed(uMaterials, uPreviousMaterials, vCoarseUv, uRing + 1, vCoarseRemaining),
                        vBlend);
    }
    albedo *= detailFactor(vLocal, vRelative, materials, n);
#endif
    fragColour = vec4(litAndHazed(albedo, n, vRelative, vec2(colour.a, vSkyVisibility)), 1.0);
}
