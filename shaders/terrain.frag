#version 330 core
// Chunk fragment program: the node's texture blended with its parent's by the morph factor (eq. 3.6,
// textural morphing), lit by the sun from the morphed normal, hazed with distance.

in vec3 vRelative;
in vec3 vNormal;
in vec2 vNodeUv;

uniform sampler2D uColour;        // the node's texture, corner texels centred on the corners (3.2.7)
uniform sampler2D uParentColour;  // the parent's texture
uniform vec2 uParentOffset;       // the node's quadrant in the parent's square: (0 or 0.5, 0 or 0.5)
uniform float uTexels;            // texels per side
uniform float uMorph;
uniform vec3 uSunDirection;       // unit, towards the sun
uniform vec3 uSunColour;
uniform vec3 uAmbient;
uniform vec3 uHazeColour;
uniform float uHazeDistance;      // metres at which haze reaches 63 %
#ifdef CLIP_TO_VALID
uniform vec4 uValidRect;          // camera-relative x0, y0, x1, y1 of the input's samples (padding excluded)
#endif
uniform int uWireframe;

out vec4 fragColour;

vec2 texelCentre(vec2 p) { return (p * (uTexels - 1.0) + 0.5) / uTexels; }

void main()
{
#ifdef CLIP_TO_VALID
    // Padding added by prep to make the grid square. Only maps with padding get this variant: a discard
    // turns off early depth testing, and with it the gain of drawing front to back (3.2.11).
    if (vRelative.x < uValidRect.x || vRelative.y < uValidRect.y || vRelative.x > uValidRect.z ||
        vRelative.y > uValidRect.w) {
        discard;
    }
#endif
    if (uWireframe != 0) {
        fragColour = vec4(0.05, 0.05, 0.05, 1.0);
        return;
    }
    vec3 own = texture(uColour, texelCentre(vNodeUv)).rgb;
    vec3 parent = texture(uParentColour, texelCentre(uParentOffset + 0.5 * vNodeUv)).rgb;
    vec3 albedo = mix(parent, own, uMorph);
    vec3 n = normalize(vNormal);
    vec3 light = uAmbient * (0.6 + 0.4 * n.z) + uSunColour * max(dot(n, uSunDirection), 0.0);
    vec3 colour = albedo * light;
    float haze = 1.0 - exp(-length(vRelative) / uHazeDistance);
    fragColour = vec4(mix(colour, uHazeColour, haze), 1.0);
}
