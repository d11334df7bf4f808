#version 330 core
// Overlay text and panels in pixel coordinates (origin top-left).
layout(location = 0) in vec2 aPosition;
layout(location = 1) in vec4 aColour;

uniform vec2 uViewport;

out vec4 vColour;

void main()
{
    vColour = aColour;
    gl_Position = vec4(aPosition.x / uViewport.x * 2.0 - 1.0, 1.0 - aPosition.y / uViewport.y * 2.0, 0.0, 1.0);
}
