#version 330 core
// A triangle over the whole viewport: one fragment per cell of the table being filled (atmosphere_table.frag).
void main()
{
    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2) * 2.0 - 1.0;
    gl_Position = vec4(p, 0.0, 1.0);
}
