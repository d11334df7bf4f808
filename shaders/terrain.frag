#version 330 core
#ifdef PIXEL_COUNTS
// Visible pixels per drawn node (issue 16; Özak & Demir, seed 001, method 2): each fragment that passes the
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
flat in float vMorph;
flat in vec2 vParentOffset;  // the node's quadrant in the parent's square: (0 or 0.5, 0 or 0.5)
flat in ivec2 vSlots;        // own, parent's layer of uColour
#ifdef PIXEL_COUNTS
layout(early_fragment_tests) in;
flat in int vInstance;  // the node's index in the frame's draw order
layout(std430, binding = 0) buffer PixelCounts { uint uPixelCounts[]; };
#endif

uniform sampler2DArray uColour;   // per slot: the node's texture, corner texels centred on the corners (3.2.7)
uniform float uTexels;            // texels per side of a node's texture
uniform float uLayerTexels;       // texels per side of a layer (>= uTexels: DXT1 pads to a multiple of 4)
#ifdef NORMAL_MAP
uniform sampler2DArray uNormalMaps;  // per slot: unit normals (x, y) of the surface below, corner texels on corners
uniform float uNormalTexels;         // texels per side of a normal map
#endif
uniform vec3 uSunDirection;       // unit, towards the sun
uniform vec3 uSunColour;
uniform vec3 uAmbient;
uniform vec3 uHazeColour;
uniform float uHazeDistance;      // metres at which haze reaches 63 %
#ifdef CLIP_TO_VALID
uniform vec4 uValidRect;          // camera-relative x0, y0, x1, y1 of the input's samples (padding excluded)
#endif
uniform int uWireframe;
#ifdef DETAIL
// Materials' detail textures (3.4.5), so the ground up close is not a blur: gray layers of one texture
// array, mean 0.5, multiplied over the node's colour, weighted by the vertex's material weights.
const int kMaxLayers = 8;
const float kDetailContrast = 0.6;
// LAYER_COUNT (1..kMaxLayers) is defined by the renderer: a loop of constant length, unrolled. With
// DETAIL_TINT_ONLY (nodes beyond every layer's fade) the layers are left out and only the tint applies.
#ifndef DETAIL_TINT_ONLY
flat in vec4 vLayerOrigin[LAYER_COUNT];  // the node's corner in repeats (xy) and in turned repeats (zw), fractional
#endif
uniform sampler2DArray uDetail;
uniform vec4 uLayerMaterialMask[kMaxLayers];  // which material a layer belongs to, as a one-hot vec4
uniform float uLayerScale[kMaxLayers];   // 1 / metres per repeat
// Each layer is sampled twice, the second time turned and scaled by this (TerrainRenderer.cpp, kDetailTurn:
// an irrational angle and scale), and the two averaged: the sum of two lattices that share no period has none,
// so the tile does not show as a regular pattern up close.
uniform mat2 uDetailTurn;
uniform vec4 uMaterialTintColumns[3];    // r, g, b of the 4 materials' tints, brightness-preserving and applied at
                                         // kTintStrength (TerrainRenderer.cpp): the map's colours stay the base


vec3 detailFactor()
{
    // Per material: the product of its layers (1 where faded out). No branch per fragment, no indexing by
    // a varying; whole nodes beyond the fade use the DETAIL_TINT_ONLY variant. The tint applies at every
    // distance, so the switch leaves no seam.
    vec4 layers = vec4(1.0);
#ifndef DETAIL_TINT_ONLY
    {
    float distance = length(vRelative);
    for (int k = 0; k < LAYER_COUNT; ++k) {
        // Gray 0.5 is neutral; kDetailContrast scales the rest, so the tile modulates the node's colour
        // rather than replacing it. Faded out between 10 and 40 repeats away: farther, the repetition of
        // the tile would show as a regular pattern, and the node's own texture carries what matters there.
        float scale = uLayerScale[k];
        vec2 p = vLocal * scale;
        // The mean of the two samples, its contrast restored (sqrt 2: they are independent).
        float g = 1.41421356 * (texture(uDetail, vec3(vLayerOrigin[k].xy + p, float(k))).r +
                                texture(uDetail, vec3(vLayerOrigin[k].zw + uDetailTurn * p, float(k))).r - 1.0);
        float amount = kDetailContrast * (1.0 - smoothstep(10.0, 40.0, distance * scale));
        layers *= vec4(1.0) + uLayerMaterialMask[k] * (amount * g);
    }
    }
#endif
    float total = dot(vMaterials, vec4(1.0));
    vec4 weighted = vMaterials * layers;
    vec3 sum = vec3(dot(weighted, uMaterialTintColumns[0]), dot(weighted, uMaterialTintColumns[1]),
                    dot(weighted, uMaterialTintColumns[2]));
    return total > 0.0 ? sum / total : vec3(1.0);
}
#endif

out vec4 fragColour;

vec2 texelCentre(vec2 p) { return (p * (uTexels - 1.0) + 0.5) / uLayerTexels; }
#ifdef NORMAL_MAP
vec3 mappedNormal()
{
    vec2 own = texture(uNormalMaps, vec3((vNodeUv * (uNormalTexels - 1.0) + 0.5) / uNormalTexels, float(vSlots.x))).xy;
    vec2 parent = texture(uNormalMaps, vec3(((vParentOffset + 0.5 * vNodeUv) * (uNormalTexels - 1.0) + 0.5) /
                                                uNormalTexels, float(vSlots.y))).xy;
    vec2 n = mix(parent, own, vMorph);
    return vec3(n, sqrt(max(1.0 - dot(n, n), 0.0)));
}
#endif

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
    vec3 own = texture(uColour, vec3(texelCentre(vNodeUv), float(vSlots.x))).rgb;
    vec3 parent = texture(uColour, vec3(texelCentre(vParentOffset + 0.5 * vNodeUv), float(vSlots.y))).rgb;
    vec3 albedo = mix(parent, own, vMorph);
#ifdef DETAIL
    albedo *= detailFactor();
#endif
#ifdef NORMAL_MAP
    vec3 n = normalize(mappedNormal());
#else
    vec3 n = normalize(vNormal);
#endif
    vec3 light = uAmbient * (0.6 + 0.4 * n.z) + uSunColour * max(dot(n, uSunDirection), 0.0);
    vec3 colour = albedo * light;
    float haze = 1.0 - exp(-length(vRelative) / uHazeDistance);
    fragColour = vec4(mix(colour, uHazeColour, haze), 1.0);
}
