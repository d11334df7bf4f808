#version 330 core
// Sky gradient: haze colour at and below the horizon, deepening blue towards the zenith, a soft sun.
in vec3 vDirection;

uniform vec3 uHazeColour;
uniform vec3 uZenithColour;
uniform vec3 uSunDirection;
uniform vec3 uSunColour;

out vec4 fragColour;

void main()
{
    vec3 direction = normalize(vDirection);
    float elevation = max(direction.z, 0.0);
    vec3 colour = mix(uHazeColour, uZenithColour, pow(elevation, 0.6));
    float sun = max(dot(direction, uSunDirection), 0.0);
    colour += uSunColour * (pow(sun, 600.0) * 2.0 + pow(sun, 12.0) * 0.15);
    fragColour = vec4(colour, 1.0);
}
