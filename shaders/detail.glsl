// Included by shaders/terrain.frag and shaders/clipmap.frag inside #ifdef DETAIL (render/DetailLayers.h): the
// materials' detail textures (3.4.5), so the ground up close is not a blur: gray layers of one texture array,
// mean 0.5, multiplied over the terrain's colour, weighted by the material weights. The includer defines
// LAYER_ORIGIN(k), layer k's texture coordinates at the point `local` counts from (DetailLayers::origin),
// unless DETAIL_TINT_ONLY.
const int kMaxLayers = 8;
const float kDetailContrast = 0.6;
// LAYER_COUNT (1..kMaxLayers) is defined by the renderer: a loop of constant length, unrolled. With
// DETAIL_TINT_ONLY (ground beyond every layer's fade) the layers are left out and only the tint applies.
uniform sampler2DArray uDetail;
uniform vec4 uLayerMaterialMask[kMaxLayers];  // which material a layer belongs to, as a one-hot vec4
uniform float uLayerScale[kMaxLayers];   // 1 / metres per repeat
// Each layer is sampled twice, the second time turned and scaled by this (DetailLayers.cpp, kDetailTurn:
// an irrational angle and scale), and the two averaged: the sum of two lattices that share no period has none,
// so the tile does not show as a regular pattern up close.
uniform mat2 uDetailTurn;
uniform vec4 uMaterialTintColumns[3];    // r, g, b of the 4 materials' tints, brightness-preserving and applied at
                                         // kTintStrength (DetailLayers.cpp): the map's colours stay the base

// The factor over the colour at `local` metres from the layers' origin, with material weights `materials`,
// `distance` metres from the viewer.
vec3 detailFactor(vec2 local, vec4 materials, float distance)
{
    // Per material: the product of its layers (1 where faded out). No branch per fragment, no indexing by
    // a varying; ground wholly beyond the fade uses the DETAIL_TINT_ONLY variant. The tint applies at every
    // distance, so the switch leaves no seam.
    vec4 layers = vec4(1.0);
#ifndef DETAIL_TINT_ONLY
    for (int k = 0; k < LAYER_COUNT; ++k) {
        // Gray 0.5 is neutral; kDetailContrast scales the rest, so the tile modulates the colour rather than
        // replacing it. Faded out between 10 and 40 repeats away: farther, the repetition of the tile would
        // show as a regular pattern, and the terrain's own texture carries what matters there.
        float scale = uLayerScale[k];
        vec2 p = local * scale;
        // The mean of the two samples, its contrast restored (sqrt 2: they are independent).
        float g = 1.41421356 * (texture(uDetail, vec3(LAYER_ORIGIN(k).xy + p, float(k))).r +
                                texture(uDetail, vec3(LAYER_ORIGIN(k).zw + uDetailTurn * p, float(k))).r - 1.0);
        float amount = kDetailContrast * (1.0 - smoothstep(10.0, 40.0, distance * scale));
        layers *= vec4(1.0) + uLayerMaterialMask[k] * (amount * g);
    }
#endif
    float total = dot(materials, vec4(1.0));
    vec4 weighted = materials * layers;
    vec3 sum = vec3(dot(weighted, uMaterialTintColumns[0]), dot(weighted, uMaterialTintColumns[1]),
                    dot(weighted, uMaterialTintColumns[2]));
    return total > 0.0 ? sum / total : vec3(1.0);
}
