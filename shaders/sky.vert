#version 330 core
// A full-screen triangle carrying each corner's view direction; the fragment program only normalises it.
uniform mat4 uInverseViewProjection;  // clip -> camera-relative world (rotation and projection only)

out vec3 vDirection;

void main()
{
    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2) * 2.0 - 1.0;
    vec4 far = uInverseViewProjection * vec4(p, 1.0, 1.0);
    vec4 near = uInverseViewProjection * vec4(p, -1.0, 1.0);
    vDirection = far.xyz / far.w - near.xyz / near.w;  // linear in screen space, so it interpolates exactly
    gl_Position = vec4(p, 1.0, 1.0);
}
