#version 400 core
// Tessellation control: the block's level and its sides' lattices come from the CPU
// (lod/TessellationLevels.h, chooseBlockLevels, one 16-bit code per block of every drawn node), so what is
// drawn is exactly what the error meter measures. A block at level t is tessellated uniformly into
// (B / 2^t)^2 cells (all six levels equal: no transition triangles); a skirt patch into B / 2^t columns. Culled
// blocks get level 0 and are dropped.

layout(vertices = 1) out;

in float cPatch[];
in float cInstance[];
in vec4 cNode0[];
in vec4 cNode1[];
in vec4 cNode2[];
#ifdef DETAIL
in vec4 cLayer0[];
in vec4 cLayer1[];
in vec4 cLayer2[];
in vec4 cLayer3[];
in vec4 cLayer4[];
in vec4 cLayer5[];
in vec4 cLayer6[];
in vec4 cLayer7[];
patch out vec4 eLayerOrigin[8];
#endif

uniform usamplerBuffer uLevels;  // per drawn node, B^2 block codes (BlockLevels::code)
uniform int uFirstInstance;      // the draw's first node in uLevels
uniform int uBlocks;             // B: blocks per side
uniform int uBlockQuads;         // quads per block side

patch out vec4 eNode0;
patch out vec4 eNode1;
patch out vec4 eNode2;
patch out ivec4 eBlock;  // bx, by, kind (0 surface, 1 + side for a skirt), level t
patch out ivec4 eSnap;   // the lattice of the south, east, north and west sides
#ifdef PIXEL_COUNTS
patch out int eInstance;  // the node's index in the frame's order (terrain.frag, uPixelCounts)
#endif

void main()
{
    int id = int(cPatch[0]);
    int b = uBlocks;
    int kind = 0;
    ivec2 block;
    if (id < b * b) {
        block = ivec2(id % b, id / b);
    } else {
        int side = (id - b * b) / b;
        int k = (id - b * b) % b;
        kind = 1 + side;
        block = side == 0 ? ivec2(k, 0) : side == 1 ? ivec2(b - 1, k) : side == 2 ? ivec2(k, b - 1) : ivec2(0, k);
    }
    int code = int(texelFetch(uLevels, (uFirstInstance + int(cInstance[0])) * b * b + block.y * b + block.x).r);
    int t = code & BLOCK_LEVEL_MASK;
    eBlock = ivec4(block, kind, t);
    const int snapMask = (1 << BLOCK_SNAP_BITS) - 1;
    eSnap = ivec4(code >> BLOCK_SNAP_SHIFT, code >> (BLOCK_SNAP_SHIFT + BLOCK_SNAP_BITS),
                  code >> (BLOCK_SNAP_SHIFT + 2 * BLOCK_SNAP_BITS), code >> (BLOCK_SNAP_SHIFT + 3 * BLOCK_SNAP_BITS)) &
            snapMask;
#ifdef PIXEL_COUNTS
    eInstance = uFirstInstance + int(cInstance[0]);
#endif
    eNode0 = cNode0[0];
    eNode1 = cNode1[0];
    eNode2 = cNode2[0];
#ifdef DETAIL
    eLayerOrigin[0] = cLayer0[0];
    eLayerOrigin[1] = cLayer1[0];
    eLayerOrigin[2] = cLayer2[0];
    eLayerOrigin[3] = cLayer3[0];
    eLayerOrigin[4] = cLayer4[0];
    eLayerOrigin[5] = cLayer5[0];
    eLayerOrigin[6] = cLayer6[0];
    eLayerOrigin[7] = cLayer7[0];
#endif
    float f = float(uBlockQuads >> t);
    if ((code & BLOCK_CULLED_BIT) != 0) {
        f = 0.0;  // culled: the patch is dropped
    }
    if (kind == 0) {
        gl_TessLevelOuter[0] = f;
        gl_TessLevelOuter[1] = f;
        gl_TessLevelOuter[2] = f;
        gl_TessLevelOuter[3] = f;
        gl_TessLevelInner[0] = f;
        gl_TessLevelInner[1] = f;
    } else {
        // u along the side, v up the skirt.
        gl_TessLevelOuter[0] = f > 0.0 ? 1.0 : 0.0;
        gl_TessLevelOuter[1] = f;
        gl_TessLevelOuter[2] = f > 0.0 ? 1.0 : 0.0;
        gl_TessLevelOuter[3] = f;
        gl_TessLevelInner[0] = f;
        gl_TessLevelInner[1] = 1.0;
    }
}
