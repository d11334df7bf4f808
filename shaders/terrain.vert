#version 330 core
// Chunk vertex program (paper 3.2.8-3.2.9), one instance per drawn node: the shared template mesh becomes
// the node by scale, camera-relative translation and the node's heights (eq. 3.7). Node data lives in the
// renderer's pools: the node's surface window in one layer of a texture array, its constants per instance in the
// frame's constants buffer (aNode0..2), so all nodes of a pool go in one instanced draw (render_mode = blocks:
// one multi-draw, a command per node with the node's triangles of the template, gpudata/BlockTriangles.h). Every
// vertex geomorphs between the parent's surface and its own height (eq. 3.4, morph factor of eq. 3.5), and its
// normal with it (surface.glsl, shared with terrain.tese).

layout(location = GRID_LOCATION) in ivec2 aGrid;  // template vertex (i, j): i east, j north, 0 .. N-1
layout(location = SKIRT_LOCATION) in int aSkirt;  // 1: skirt vertex hanging below the edge vertex (3.2.6)
// Per instance (drawn node), from the frame's constants buffer (render/ShaderContract.h, NodeInstance):
// aNode0: origin x, y (the node's south-west corner minus the camera, metres), spacing (metres), morph;
// aNode1: skirt depth (metres), layer (in its pool array), the parent's layer (in its), lowest height (metres);
// aNode2: the node's quadrant in the parent's square (0 or 0.5, 0 or 0.5), height range (metres), the node's
// place in the frame's drawing order.
layout(location = NODE0_LOCATION) in vec4 aNode0;
layout(location = NODE1_LOCATION) in vec4 aNode1;
layout(location = NODE2_LOCATION) in vec4 aNode2;
#ifdef DETAIL
// The node's corner in repeats of each detail layer, fractional part (xy), and in the layer's tiling lattice,
// modulo its period (zw: detail.glsl, DetailLayers::origin), an attribute a layer.
layout(location = LAYER_ORIGIN_LOCATION) in vec4 aLayerOrigin[LAYER_COUNT];
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
flat out int vInstance;
#endif
#ifdef DETAIL
flat out vec4 vLayerOrigin[LAYER_COUNT];
#endif

#ifdef SHADOWS
out float vSkyVisibility;  // the share of the sky the terrain around leaves the vertex, morphed (surface.glsl)
#endif
#ifdef ATMOSPHERE
out vec3 vSunlight;  // the air at the vertex (atmosphere.glsl, Air)
out vec3 vAirTransmittance;
out vec3 vAerial;
#endif

#include "atmosphere.glsl"
#include "light.glsl"
#include "surface.glsl"

void main()
{
    emitSurfaceVertex(aGrid, aNode0, aNode1, aNode2, float(aSkirt));
#ifdef DETAIL
    for (int k = 0; k < LAYER_COUNT; ++k) {
        vLayerOrigin[k] = aLayerOrigin[k];
    }
#endif
#ifdef PIXEL_COUNTS
    vInstance = int(aNode2.w);
#endif
}
