// Included by shaders/terrain.frag and shaders/clipmap.frag inside #ifdef DETAIL (render/DetailLayers.h): the
// materials' detail textures (3.4.5), so the ground up close is not a blur: gray layers of one texture array,
// multiplied over the terrain's colour (which carries the materials' ground colours already: synthesis
// coverTexture), weighted by the material weights. The includer defines LAYER_ORIGIN(k), layer k's coordinates at
// the point `local` counts from (DetailLayers::origin). Ground beyond every layer's fade is drawn by a program
// without DETAIL.
//
// No tile: each layer is sampled by tiling and blending with histogram preservation (Heitz & Neyret 2018). The
// plane is cut into a lattice of triangles a layer's repeat wide; each lattice vertex shows the texture at its
// own random offset (an integer hash of the vertex), and a point blends the three of its triangle by its
// barycentric weights w, as (sum w t - mean) / sqrt(sum w^2) + mean, which keeps the deviation of one sample.
// The textures are made Gaussian when they are loaded (DetailLayers.cpp), and a variance-preserving blend of
// Gaussian values is Gaussian with the same mean and deviation: the histogram is kept without a lookup. Only the
// layers of the fragment's dominant material are sampled (three fetches a layer); the others count as flat.
const int kMaxLayers = 8;
const float kDetailContrast = 0.6;
// LAYER_COUNT (1..kMaxLayers) is defined by the renderer: a loop of constant length, unrolled.
uniform sampler2DArray uDetail;
uniform vec4 uLayerMaterialMask[kMaxLayers];  // which material a layer belongs to, as a one-hot vec4
uniform float uLayerScale[kMaxLayers];        // 1 / metres per repeat
uniform float uLayerMean[kMaxLayers];         // the layer's mean gray
// Repeats to lattice coordinates (DetailLayers.cpp, kLatticeFromRepeats): the triangle lattice's vertices are the
// integer points, and each cell of the unit square holds two of its triangles.
uniform mat2 uLatticeFromRepeats;

// A lattice vertex's offset in [0, 1)^2 (Jarzynski & Olano 2020's pcg2d). Vertices count modulo 4096 (as
// DetailLayers::origin reduces them), so neighbouring nodes agree on every vertex.
vec2 latticeOffset(ivec2 vertex)
{
    uvec2 v = uvec2(vertex & 4095) * 1664525u + 1013904223u;
    v.x += v.y * 1664525u;
    v.y += v.x * 1664525u;
    v = v ^ (v >> 16u);
    v.x += v.y * 1664525u;
    v.y += v.x * 1664525u;
    v = v ^ (v >> 16u);
    return vec2(v >> 8u) * (1.0 / 16777216.0);
}

// Layer k at `uv` (repeats, the texture's coordinates) and `lattice` (the same point in lattice coordinates),
// minus its mean: the histogram-preserving blend of the three lattice vertices around the point.
float tiledDetail(int k, vec2 uv, vec2 lattice)
{
    // One level of detail for the three fetches, from the point's own footprint (the offsets jump between
    // triangles, so the fetches' implicit derivatives would not be the footprint's): the hardware's rule.
    vec2 footprint = vec2(textureSize(uDetail, 0).xy);
    vec2 dx = dFdx(uv) * footprint, dy = dFdy(uv) * footprint;
    float lod = 0.5 * log2(max(max(dot(dx, dx), dot(dy, dy)), 1e-8));
    ivec2 cell = ivec2(floor(lattice));
    vec2 f = lattice - vec2(cell);
    // The cell's lower-left triangle (0,0), (1,0), (0,1), or its upper-right one (1,1), (0,1), (1,0).
    bool upper = f.x + f.y > 1.0;
    ivec2 a = upper ? cell + ivec2(1, 1) : cell;
    vec3 w = upper ? vec3(f.x + f.y - 1.0, 1.0 - f.x, 1.0 - f.y) : vec3(1.0 - f.x - f.y, f.x, f.y);
    ivec2 b = upper ? cell + ivec2(0, 1) : cell + ivec2(1, 0);
    ivec2 c = upper ? cell + ivec2(1, 0) : cell + ivec2(0, 1);
    float sum = w.x * textureLod(uDetail, vec3(uv + latticeOffset(a), float(k)), lod).r +
                w.y * textureLod(uDetail, vec3(uv + latticeOffset(b), float(k)), lod).r +
                w.z * textureLod(uDetail, vec3(uv + latticeOffset(c), float(k)), lod).r;
    return (sum - uLayerMean[k]) * inversesqrt(dot(w, w));
}

// The factor over the colour at `local` metres from the layers' origin, with material weights `materials`,
// `distance` metres from the viewer.
float detailFactor(vec2 local, vec4 materials, float distance)
{
    // Per material: the product of its layers (1 where faded out, and for every material but the dominant one).
    vec4 layers = vec4(1.0);
    // The dominant material, one-hot (of equal weights the first).
    vec4 dominant = vec4(1.0, 0.0, 0.0, 0.0);
    float top = materials.x;
    if (materials.y > top) {
        dominant = vec4(0.0, 1.0, 0.0, 0.0);
        top = materials.y;
    }
    if (materials.z > top) {
        dominant = vec4(0.0, 0.0, 1.0, 0.0);
        top = materials.z;
    }
    if (materials.w > top) {
        dominant = vec4(0.0, 0.0, 0.0, 1.0);
    }
    for (int k = 0; k < LAYER_COUNT; ++k) {
        // Gray at the mean is neutral; kDetailContrast scales the rest, so the layer modulates the colour rather
        // than replacing it. Faded out between 10 and 40 repeats away, where the terrain's own texture carries
        // what matters.
        float scale = uLayerScale[k];
        float amount = kDetailContrast * (1.0 - smoothstep(10.0, 40.0, distance * scale));
        if (dot(uLayerMaterialMask[k], dominant) > 0.0 && amount > 0.0) {
            vec2 p = local * scale;
            vec4 origin = LAYER_ORIGIN(k);
            // Twice the deviation from the mean, the contrast two independent samples of the tile had.
            float g = 2.0 * tiledDetail(k, origin.xy + p, origin.zw + uLatticeFromRepeats * p);
            layers *= vec4(1.0) + uLayerMaterialMask[k] * (amount * g);
        }
    }
    float total = dot(materials, vec4(1.0));
    return total > 0.0 ? dot(materials, layers) / total : 1.0;
}
