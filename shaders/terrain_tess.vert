#version 400 core
// Tessellation mode (render_mode = tessellation): one patch per tessellation block of a drawn node
// and one per block side on the node's border (its skirt), one instance per node. This stage only hands the
// patch number and the node's constants (the same per-instance attributes as terrain.vert) to the control
// shader (terrain.tesc); terrain.tese makes the vertices.

layout(location = PATCH_LOCATION) in float aPatch;  // 0 .. B^2 - 1: block by * B + bx; B^2 + side * B + k: skirt
layout(location = NODE0_LOCATION) in vec4 aNode0;
layout(location = NODE1_LOCATION) in vec4 aNode1;
layout(location = NODE2_LOCATION) in vec4 aNode2;
#ifdef DETAIL
layout(location = LAYER_ORIGIN_LOCATION) in vec4 aLayerOrigin[LAYER_COUNT];
// Up to 8 (kMaxLayers): arrays of arrays (one per patch vertex) need GLSL 4.30.
out vec4 cLayer0;
out vec4 cLayer1;
out vec4 cLayer2;
out vec4 cLayer3;
out vec4 cLayer4;
out vec4 cLayer5;
out vec4 cLayer6;
out vec4 cLayer7;
#endif

uniform int uFirstPatch;  // the draw's first patch (TerrainRenderer::drawPatchRanges): aPatch counts from it

out float cPatch;
out float cInstance;
out vec4 cNode0;
out vec4 cNode1;
out vec4 cNode2;

void main()
{
    cPatch = aPatch + float(uFirstPatch);
    cInstance = float(gl_InstanceID);
    cNode0 = aNode0;
    cNode1 = aNode1;
    cNode2 = aNode2;
#ifdef DETAIL
    vec4 layers[8] = vec4[8](vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0), vec4(0.0));
    for (int k = 0; k < LAYER_COUNT; ++k) {
        layers[k] = aLayerOrigin[k];
    }
    cLayer0 = layers[0];
    cLayer1 = layers[1];
    cLayer2 = layers[2];
    cLayer3 = layers[3];
    cLayer4 = layers[4];
    cLayer5 = layers[5];
    cLayer6 = layers[6];
    cLayer7 = layers[7];
#endif
    gl_Position = vec4(0.0);
}
