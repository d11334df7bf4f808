// A drawn node's surface at one of its samples, geomorphed (paper 3.2.8, eq. 3.4): shared by the chunk vertex
// program (terrain.vert) and the tessellation evaluation program (terrain.tese), which make the same vertices
// from the same arithmetic. The node's data lives in the renderer's pools (its surface window, the parent's
// normals, the material weights); its constants are a NodeInstance (render/ShaderContract.h). The parent's
// surface is the node's own even samples (they are the parent's samples) along the template triangulation; its
// normals at its samples are made with the node (lod/NodeTextures.h), and between parent samples the mean of the
// two is taken (gpudata/NodeVertexData.h computes the same on the CPU). The includer declares the outputs written
// here: vRelative, vNormal (without NORMAL_MAP), vNodeUv, vLocal, vMaterials, vMorph, vParentOffset, vSlots, with
// SHADOWS vSkyVisibility, and with ATMOSPHERE the air at the vertex (atmosphere.glsl, airAt): vSunlight,
// vAirTransmittance, vAerial.

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
#ifdef SHADOWS
// per slot: N x N visibilities of the sky at the node's samples (r) and at the same places on its parent's surface
// (g), from the nodes' horizons (lod/NodeHorizons.h); the sun's rides in the colour's alpha (terrain.frag)
uniform sampler2DArray uLight;
#endif

int gSlot;
float gLo, gRange;  // the slot's heights: lo + range * code / 65535 (lod/NodeTextures.h, quantizeHeightsR16)
float height(ivec2 p) { return gLo + gRange * texelFetch(uHeights, ivec3(p + 1, gSlot), 0).r; }
#ifndef NORMAL_MAP
// The parent's unit normal (x, y) at node sample p (both even).
vec2 parentNormalAt(ivec2 p) { return texelFetch(uParentNormals, ivec3(p / 2, gSlot), 0).xy; }
#endif

// Writes the outputs of node sample p of the node with constants node0 .. node2 (aNode0 .. aNode2), `drop`
// skirt depths below the surface (0 on the surface, 1 at a skirt's bottom, 3.2.6).
void emitSurfaceVertex(ivec2 p, vec4 node0, vec4 node1, vec4 node2, float drop)
{
    gSlot = int(node1.y);
    gLo = node1.w;
    gRange = node2.z;
    float spacing = node0.z;
    float morph = node0.w;

    // The two parent samples the vertex lies between (along x, y or the SW-NE diagonal); the vertex itself
    // twice at a parent sample, where the mean is the sample exactly.
    ivec2 d = p & 1;
    float own = height(p);
    float parent = 0.5 * (height(p - d) + height(p + d));
#ifndef NORMAL_MAP
    vec3 ownN = vec3(-0.5 * vec2(height(p + ivec2(1, 0)) - height(p - ivec2(1, 0)),
                                 height(p + ivec2(0, 1)) - height(p - ivec2(0, 1))) / spacing, 1.0);
    vec2 ownNormal = ownN.xy / length(ownN);
    vec2 parentNormal = 0.5 * (parentNormalAt(p - d) + parentNormalAt(p + d));
    vec2 n = mix(parentNormal, ownNormal, morph);
    vNormal = vec3(n, sqrt(max(1.0 - dot(n, n), 0.0)));
#endif
    float z = uHeightBase + mix(parent, own, morph) - drop * node1.x;
    vRelative = vec3(node0.xy + vec2(p) * spacing, z);
    vNodeUv = vec2(p) * uInverseCells;
    vLocal = vec2(p) * spacing;
#ifdef SHADOWS
    vec2 sky = texelFetch(uLight, ivec3(p, gSlot), 0).rg;
    vSkyVisibility = mix(sky.g, sky.r, morph);
#endif
#ifdef DETAIL
    vMaterials = texelFetch(uWeights, ivec3(p, gSlot), 0);
#else
    vMaterials = vec4(0.0);
#endif
    vMorph = morph;
    vParentOffset = node2.xy;
    vSlots = ivec2(gSlot, int(node1.z));
    gl_Position = uViewProjection * vec4(vRelative, 1.0);
#ifdef ATMOSPHERE
    Air air = airAt(vRelative, uSunDirection);
    vSunlight = air.sunlight;
    vAirTransmittance = air.transmittance;
    vAerial = air.inscattered;
#endif
}
