#version 330 core
#ifdef PIXEL_COUNTS
// Visible pixels per drawn node (Özak & Demir, seed 001, method 2): each fragment that passes the
// depth test adds one to its node's counter. The test must come before the program runs, or occluded
// fragments would count too (their side effect happens whatever the later test decides).
#extension GL_ARB_shader_storage_buffer_object : require
#extension GL_ARB_shader_image_load_store : require
#endif
// Chunk fragment program: the node's texture blended with its parent's by the morph factor (eq. 3.6,
// textural morphing), lit by the sun from the morphed normal, hazed with distance. The node's data comes
// from the vertex program (flat: the same for the whole node). With NORMAL_MAP the normal comes from the
// node's normal map (the surface below it, synthesis/NormalMap.h) blended with its parent's like the
// colours; without, from the vertex program's morphed vertex normals.

in vec3 vRelative;
#ifndef NORMAL_MAP
in vec3 vNormal;
#endif
in vec2 vNodeUv;
in vec2 vLocal;
in vec4 vMaterials;
#ifdef ATMOSPHERE
in vec3 vSunlight;  // the air at the fragment, interpolated between the vertices' (atmosphere.glsl, Air; its
                    // skylight, a lookup by altitude, is made here)
in vec3 vAirTransmittance;
in vec3 vAerial;
#endif

flat in float vMorph;
flat in vec2 vParentOffset;  // the node's quadrant in the parent's square: (0 or 0.5, 0 or 0.5)
flat in ivec2 vSlots;        // layers: the node's in uColour, its parent's in uParentColour
#ifdef PIXEL_COUNTS
layout(early_fragment_tests) in;
flat in int vInstance;  // the node's index in the frame's draw order
layout(std430, binding = 0) buffer PixelCounts { uint uPixelCounts[]; };
#endif

uniform sampler2DArray uColour;   // per slot: the node's texture, corner texels centred on the corners (3.2.7);
                                  // with SHADOWS the sun's visibility in alpha (1 without: RGB layers)
uniform sampler2DArray uParentColour;  // the same textures in the parent's pool array
uniform float uTexels;            // texels per side of a node's texture
uniform float uLayerTexels;       // texels per side of a layer (>= uTexels: DXT1 pads to a multiple of 4)
#ifdef SHADOWS
// The sky's visibility, morphed, from the vertices (surface.glsl). The sun's is the colour's alpha, derived from
// the nodes' horizons for the frame's sun (lod/NodeHorizons.h): the same fetch as the colour, own and parent's.
in float vSkyVisibility;
#endif
#ifdef NORMAL_MAP
uniform sampler2DArray uNormalMaps;  // per slot: unit normals (x, y) of the surface below, corner texels on corners
uniform sampler2DArray uParentNormalMaps;  // the same maps in the parent's pool array
uniform float uNormalTexels;         // texels per side of a normal map
uniform float uNormalLayerTexels;    // texels per side of a layer (>= uNormalTexels: RGTC2 pads to a multiple of 4)
#endif
#ifdef CLIP_TO_VALID
uniform vec4 uValidRect;          // camera-relative x0, y0, x1, y1 of the input's samples (padding excluded)
#endif
uniform int uWireframe;
#ifdef DETAIL
// The materials' detail textures (render/DetailLayers.h), with the node's corner in each layer's repeats.
flat in vec4 vLayerOrigin[LAYER_COUNT];  // the node's corner in repeats (xy) and lattice coordinates (zw), reduced
#define LAYER_ORIGIN(k) vLayerOrigin[k]
#include "detail.glsl"
#endif
#include "atmosphere.glsl"
#include "light.glsl"

out vec4 fragColour;

vec2 texelCentre(vec2 p) { return (p * (uTexels - 1.0) + 0.5) / uLayerTexels; }
#ifdef NORMAL_MAP
vec3 mappedNormal()
{
    vec2 own = texture(uNormalMaps, vec3((vNodeUv * (uNormalTexels - 1.0) + 0.5) / uNormalLayerTexels,
                                         float(vSlots.x))).xy;
    vec2 parent = texture(uParentNormalMaps, vec3(((vParentOffset + 0.5 * vNodeUv) * (uNormalTexels - 1.0) + 0.5) /
                                                uNormalLayerTexels, float(vSlots.y))).xy;
    vec2 n = mix(parent, own, vMorph);
    return vec3(n, sqrt(max(1.0 - dot(n, n), 0.0)));
}
#endif

// The share of the sun (x) and of the sky (y) the terrain around leaves the fragment, morphed like the colours:
// the sun's from the node's colour `own` and its parent's `parent`.
vec2 visibility(vec4 own, vec4 parent)
{
#ifdef SHADOWS
    return vec2(mix(parent.a, own.a, vMorph), vSkyVisibility);
#else
    return vec2(1.0);
#endif
}

void main()
{
#ifdef CLIP_TO_VALID
    // Padding added by prep to make the grid square. Only maps with padding get this variant: a discard
    // turns off early depth testing, and with it the gain of drawing front to back (3.2.11).
    if (vRelative.x < uValidRect.x || vRelative.y < uValidRect.y || vRelative.x > uValidRect.z ||
        vRelative.y > uValidRect.w) {
        discard;
    }
#endif
#ifdef PIXEL_COUNTS
    // With early tests a discarded fragment above has written its depth already: padding outside the
    // input's samples still hides what lies behind it, which is only more padding while the camera is
    // above the input (its samples form a rectangle, and a ray leaving it does not come back).
    atomicAdd(uPixelCounts[vInstance], 1u);
#endif
    if (uWireframe != 0) {
        fragColour = vec4(0.05, 0.05, 0.05, 1.0);
        return;
    }
    vec4 own = texture(uColour, vec3(texelCentre(vNodeUv), float(vSlots.x)));
    vec4 parent = texture(uParentColour, vec3(texelCentre(vParentOffset + 0.5 * vNodeUv), float(vSlots.y)));
    vec3 albedo = mix(parent.rgb, own.rgb, vMorph);
#ifdef NORMAL_MAP
    vec3 n = normalize(mappedNormal());
#else
    vec3 n = normalize(vNormal);
#endif
#ifdef DETAIL
    albedo *= detailFactor(vLocal, vRelative, vMaterials, n);
#endif
#ifdef ATMOSPHERE
    Air air = Air(vSunlight, vAirTransmittance, vAerial, skyIrradianceAt(uCameraAltitude + vRelative.z));
    fragColour = vec4(litThroughAir(albedo, n, visibility(own, parent), air), 1.0);
#else
    fragColour = vec4(litAndHazed(albedo, n, vRelative, visibility(own, parent)), 1.0);
#endif
}
