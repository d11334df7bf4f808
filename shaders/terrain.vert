#version 330 core
// Chunk vertex program (paper 3.2.8-3.2.9): the shared template mesh becomes one node by scale,
// camera-relative translation and the node's heights (eq. 3.7); odd vertices geomorph between the
// parent's surface and their own height (eq. 3.4, morph factor of eq. 3.5); normals morph the same way.
// Heights are 16-bit codes in a (N + 4)^2 texture with a 2-sample border (neighbours' samples), so
// normals at the chunk's edge match its neighbours'.

layout(location = 0) in ivec2 aGrid;   // template vertex (i, j): i east, j north, 0 .. N-1
layout(location = 1) in int aSkirt;    // 1: skirt vertex hanging below the edge vertex (3.2.6)

uniform usampler2D uHeights;   // (N + 4)^2 codes, border 2
uniform mat4 uViewProjection;  // camera-relative world -> clip (rotation and projection only)
uniform vec2 uOrigin;          // the node's south-west corner minus the camera position, metres
uniform float uSpacing;        // metres between the node's samples
uniform float uHeightBase;     // metres at code 0 minus the camera's height
uniform float uHeightStep;     // metres per code
uniform float uMorph;          // eq. 3.5: 0 = the parent's surface, 1 = the node's own
uniform float uSkirtDepth;     // metres

out vec3 vRelative;   // camera-relative position, metres
out vec3 vNormal;
out vec2 vNodeUv;     // position in the node's square, 0 .. 1

float code(ivec2 p) { return float(texelFetch(uHeights, p + ivec2(2), 0).r); }

// Gradient (codes per sample) of the parent's surface at a vertex that is also a parent sample: central
// differences over two of the node's samples.
vec2 parentGradient(ivec2 p)
{
    return vec2(code(p + ivec2(2, 0)) - code(p - ivec2(2, 0)), code(p + ivec2(0, 2)) - code(p - ivec2(0, 2))) * 0.25;
}

void main()
{
    ivec2 g = aGrid;
    bool oddX = (g.x & 1) == 1;
    bool oddY = (g.y & 1) == 1;
    float own = code(g);
    // The parent's surface along the template triangulation (SW-NE diagonals, TemplateTriangulation.h).
    ivec2 stepA = ivec2(0);
    if (oddX && oddY) {
        stepA = ivec2(1, 1);
    } else if (oddX) {
        stepA = ivec2(1, 0);
    } else if (oddY) {
        stepA = ivec2(0, 1);
    }
    float parent = own;
    vec2 parentSlope;
    if (oddX || oddY) {
        parent = 0.5 * (code(g - stepA) + code(g + stepA));
        parentSlope = 0.5 * (parentGradient(g - stepA) + parentGradient(g + stepA));
    } else {
        parentSlope = parentGradient(g);
    }
    vec2 ownSlope = vec2(code(g + ivec2(1, 0)) - code(g - ivec2(1, 0)), code(g + ivec2(0, 1)) - code(g - ivec2(0, 1))) * 0.5;
    vec2 slope = mix(parentSlope, ownSlope, uMorph) * (uHeightStep / uSpacing);
    vNormal = normalize(vec3(-slope, 1.0));

    float z = uHeightBase + uHeightStep * mix(parent, own, uMorph);
    if (aSkirt != 0) {
        z -= uSkirtDepth;
    }
    vRelative = vec3(uOrigin + vec2(g) * uSpacing, z);
    vNodeUv = vec2(g) / float(textureSize(uHeights, 0).x - 5);
    gl_Position = uViewProjection * vec4(vRelative, 1.0);
}
