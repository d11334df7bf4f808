#version 330 core
// Chunk vertex program (paper 3.2.8-3.2.9), one instance per drawn node: the shared template mesh becomes
// the node by scale, camera-relative translation and the node's heights (eq. 3.7). Node data lives in the
// renderer's pools: the node's surface window in one layer of a texture array, its constants in
// a texture buffer, so all nodes go in one instanced draw. Every vertex geomorphs between the parent's
// surface and its own height (eq. 3.4, morph factor of eq. 3.5), and its normal with it. The parent's
// surface is the node's own even samples (they are the parent's samples) along the template triangulation;
// its normals at its samples are made with the node (render/NodeTextures.h), and between parent samples
// the mean of the two is taken (render/NodeVertexData.h computes the same on the CPU).

layout(location = 0) in ivec2 aGrid;  // template vertex (i, j): i east, j north, 0 .. N-1
layout(location = 1) in int aSkirt;   // 1: skirt vertex hanging below the edge vertex (3.2.6)
// Per instance (drawn node), from the frame's constants buffer (TerrainRenderer.cpp, NodeConstants):
layout(location = 2) in vec4 aNode0;  // origin x, y (the node's south-west corner minus the camera, metres),
                                      // spacing (metres), morph
layout(location = 3) in vec4 aNode1;  // skirt depth (metres), layer (in its pool array), the parent's layer (in
                                      // its), lowest height (metres)
layout(location = 4) in vec4 aNode2;  // the node's quadrant in the parent's square (0 or 0.5, 0 or 0.5),
                                      // height range (metres), 0
#if defined(DETAIL) && !defined(DETAIL_TINT_ONLY)
// The node's corner in repeats of each detail layer, fractional part (xy), and in repeats of the layer's
// turned copy (zw: terrain.frag, uDetailTurn), an attribute a layer.
layout(location = 5) in vec4 aLayerOrigin[LAYER_COUNT];
#endif

uniform mat4 uViewProjection;  // camera-relative world -> clip (rotation and projection only)
uniform float uInverseCells;   // 1 / (N - 1)
uniform float uHeightBase;     // the map's height offset minus the camera's height, metres
uniform sampler2DArray uHeights;  // per slot: the (N + 2)^2 surface window, 16-bit codes over the node's range
#ifndef NORMAL_MAP
uniform sampler2DArray uParentNormals;  // per slot: ((N + 1) / 2)^2 unit normals (x, y) of the parent
#endif
#ifdef DETAIL
uniform sampler2DArray uWeights;  // per slot: N x N material weights (3.4.5)
#endif

out vec3 vRelative;   // camera-relative position, metres
#ifndef NORMAL_MAP
out vec3 vNormal;  // with normal maps the fragment program has its normals
#endif
out vec2 vNodeUv;     // position in the node's square, 0 .. 1
out vec2 vLocal;      // metres from the node's south-west corner
out vec4 vMaterials;
flat out float vMorph;
flat out vec2 vParentOffset;
flat out ivec2 vSlots;  // layers: own (in its pool array), parent's (in its)
#ifdef PIXEL_COUNTS
uniform int uFirstInstance;  // the draw's first node in the frame's order
flat out int vInstance;
#endif
#if defined(DETAIL) && !defined(DETAIL_TINT_ONLY)
flat out vec4 vLayerOrigin[LAYER_COUNT];
#endif

int gSlot;
float gLo, gRange;  // the slot's heights: lo + range * code / 65535 (render/NodeTextures.h, quantizeHeightsR16)
float height(ivec2 p) { return gLo + gRange * texelFetch(uHeights, ivec3(p + 1, gSlot), 0).r; }
#ifndef NORMAL_MAP
// The parent's unit normal (x, y) at node sample p (both even).
vec2 parentNormalAt(ivec2 p) { return texelFetch(uParentNormals, ivec3(p / 2, gSlot), 0).xy; }
#endif

void main()
{
    vec4 t0 = aNode0;
    vec4 t1 = aNode1;
    vec4 t2 = aNode2;
    gSlot = int(t1.y);
    gLo = t1.w;
    gRange = t2.z;
    float spacing = t0.z;
    float morph = t0.w;

    // The two parent samples the vertex lies between (along x, y or the SW-NE diagonal); the vertex itself
    // twice at a parent sample, where the mean is the sample exactly.
    ivec2 d = aGrid & 1;
    float own = height(aGrid);
    float parent = 0.5 * (height(aGrid - d) + height(aGrid + d));
#ifndef NORMAL_MAP
    vec3 ownN = vec3(-0.5 * vec2(height(aGrid + ivec2(1, 0)) - height(aGrid - ivec2(1, 0)),
                                 height(aGrid + ivec2(0, 1)) - height(aGrid - ivec2(0, 1))) / spacing, 1.0);
    vec2 ownNormal = ownN.xy / length(ownN);
    vec2 parentNormal = 0.5 * (parentNormalAt(aGrid - d) + parentNormalAt(aGrid + d));

    vec2 n = mix(parentNormal, ownNormal, morph);
    vNormal = vec3(n, sqrt(max(1.0 - dot(n, n), 0.0)));
#endif
    float z = uHeightBase + mix(parent, own, morph) - float(aSkirt) * t1.x;
    vRelative = vec3(t0.xy + vec2(aGrid) * spacing, z);
    vNodeUv = vec2(aGrid) * uInverseCells;
    vLocal = vec2(aGrid) * spacing;
#ifdef DETAIL
    vMaterials = texelFetch(uWeights, ivec3(aGrid, gSlot), 0);
#ifndef DETAIL_TINT_ONLY
    for (int k = 0; k < LAYER_COUNT; ++k) {
        vLayerOrigin[k] = aLayerOrigin[k];
    }
#endif
#else
    vMaterials = vec4(0.0);
#endif
    vMorph = morph;
    vParentOffset = t2.xy;
    vSlots = ivec2(gSlot, int(t1.z));
#ifdef PIXEL_COUNTS
    vInstance = uFirstInstance + gl_InstanceID;
#endif
    gl_Position = uViewProjection * vec4(vRelative, 1.0);
}
