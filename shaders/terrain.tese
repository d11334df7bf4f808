#version 400 core
// Tessellation evaluation: the vertices of a block at level t, or of a border skirt, from the
// node's data in the pools, with the same geomorph, normals and outputs as the chunk vertex program
// (terrain.vert; terrain.frag shades both). A vertex on a block side whose lattice is coarser than t is
// snapped onto that lattice (lod/BlockErrors.h, snapToLattice and tessellatedVertex compute the same), so the
// neighbouring block makes the same vertex there, bit for bit: same sample, same arithmetic (precise).

layout(quads, equal_spacing, ccw) in;

patch in vec4 eNode0;  // as terrain.vert's aNode0 .. aNode2
patch in vec4 eNode1;
patch in vec4 eNode2;
patch in ivec4 eBlock;  // bx, by, kind (0 surface, 1 + side: skirt of the south, east, north, west border), t
patch in ivec4 eSnap;   // lattices of the south, east, north, west sides
#ifdef PIXEL_COUNTS
patch in int eInstance;
flat out int vInstance;
#endif
#ifdef DETAIL
patch in vec4 eLayerOrigin[8];
flat out vec4 vLayerOrigin[LAYER_COUNT];
#endif

uniform int uBlockQuads;

precise out vec3 vRelative;
#ifndef NORMAL_MAP
out vec3 vNormal;  // with normal maps the fragment program has its normals
#endif
out vec2 vNodeUv;
out vec2 vLocal;
out vec4 vMaterials;
flat out float vMorph;
flat out vec2 vParentOffset;
flat out ivec2 vSlots;
precise gl_Position;

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

int snapToLattice(int c, int level) { int g = 1 << level; return (c + g / 2) / g * g; }

void main()
{
    int q = uBlockQuads;
    int t = eBlock.w;
    int s = 1 << t;
    int f = q >> t;
    ivec2 origin = eBlock.xy * q;
    ivec2 p;
    float drop = 0.0;
    if (eBlock.z == 0) {
        ivec2 cell = ivec2(round(gl_TessCoord.xy * float(f)));
        p = origin + cell * s;
        bool alongX = cell.x > 0 && cell.x < f, alongY = cell.y > 0 && cell.y < f;
        if (alongX && cell.y == 0) {
            p.x = snapToLattice(p.x, eSnap.x);
        } else if (alongX && cell.y == f) {
            p.x = snapToLattice(p.x, eSnap.z);
        } else if (alongY && cell.x == 0) {
            p.y = snapToLattice(p.y, eSnap.w);
        } else if (alongY && cell.x == f) {
            p.y = snapToLattice(p.y, eSnap.y);
        }
    } else {
        // Skirt: u runs along the border with the node on its left seen from outside, v up; the bottom
        // hangs the skirt depth below the surface (3.2.6).
        int a = int(round(gl_TessCoord.x * float(f))) * s;
        int side = eBlock.z - 1;
        p = side == 0 ? origin + ivec2(a, 0)
                      : side == 1 ? origin + ivec2(q, a) : side == 2 ? origin + ivec2(q - a, q) : origin + ivec2(0, q - a);
        drop = 1.0 - gl_TessCoord.y;
    }

    emitSurfaceVertex(p, eNode0, eNode1, eNode2, drop);
    if (eBlock.z != 0) {
        // A skirt loses every tie in depth, its top included: where it meets a surface at the same depth (its own
        // node's or a neighbour's edge), the surface shows whichever is drawn first, so which node's fragment shows
        // does not depend on the order of the draws (TerrainRenderer::drawPatchRanges). Two neighbours' skirts
        // along a border face opposite ways, so one of them is culled. 2^-22 of w is 2^-23 of window depth, two
        // steps of a 24-bit depth buffer: 0.25 m behind at 1 km with a 0.5 m near plane, 24 m at 10 km (depth
        // steps grow with the square of the distance), far less than what lies behind a crack a skirt fills.
        gl_Position.z += gl_Position.w * (1.0 / 4194304.0);
    }
#ifdef DETAIL
    for (int k = 0; k < LAYER_COUNT; ++k) {
        vLayerOrigin[k] = eLayerOrigin[k];
    }
#endif
#ifdef PIXEL_COUNTS
    vInstance = eInstance;
#endif
}
