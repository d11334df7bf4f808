#version 330 core
// Chunk vertex program (paper 3.2.8-3.2.9): the shared template mesh becomes one node by scale,
// camera-relative translation and the node's heights (eq. 3.7); every vertex geomorphs between the
// parent's surface and its own height (eq. 3.4, morph factor of eq. 3.5), and its normal with it. The
// node's per-vertex data (render/NodeVertexData.h) is computed when the node is uploaded.

layout(location = 0) in ivec2 aGrid;       // template vertex (i, j): i east, j north, 0 .. N-1
layout(location = 1) in int aSkirt;        // 1: skirt vertex hanging below the edge vertex (3.2.6)
layout(location = 2) in vec2 aHeights;     // metres above the map's offset: own, parent's surface
layout(location = 3) in vec4 aNormals;     // x, y of the own and the parent's unit normals
layout(location = 4) in vec4 aMaterials;   // blend weights of up to 4 materials' detail textures (3.4.5)

uniform mat4 uViewProjection;  // camera-relative world -> clip (rotation and projection only)
uniform vec2 uOrigin;          // the node's south-west corner minus the camera position, metres
uniform float uSpacing;        // metres between the node's samples
uniform float uInverseCells;   // 1 / (N - 1)
uniform float uHeightBase;     // the map's height offset minus the camera's height, metres
uniform float uMorph;          // eq. 3.5: 0 = the parent's surface, 1 = the node's own
uniform float uSkirtDepth;     // metres

out vec3 vRelative;   // camera-relative position, metres
out vec3 vNormal;
out vec2 vNodeUv;     // position in the node's square, 0 .. 1
out vec2 vLocal;      // metres from the node's south-west corner
out vec4 vMaterials;

void main()
{
    vec2 n = mix(aNormals.zw, aNormals.xy, uMorph);
    vNormal = vec3(n, sqrt(max(1.0 - dot(n, n), 0.0)));
    float z = uHeightBase + mix(aHeights.y, aHeights.x, uMorph) - float(aSkirt) * uSkirtDepth;
    vRelative = vec3(uOrigin + vec2(aGrid) * uSpacing, z);
    vNodeUv = vec2(aGrid) * uInverseCells;
    vLocal = vec2(aGrid) * uSpacing;
    vMaterials = aMaterials;
    gl_Position = uViewProjection * vec4(vRelative, 1.0);
}
