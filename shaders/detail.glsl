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
//
// One projection on cliffs: ground whose normal leans further from the vertical than kCliff (a cosine) shows its
// layers projected onto a vertical plane, x-z or y-z, the one the normal faces most, so that a cliff's detail is
// not stretched down its face. Every fragment samples one projection, chosen without a branch, three fetches a
// layer (blending projections would fetch for all of them: a CPU rasterizer runs both sides of a branch). Where
// the projection changes, one Gaussian texture meets another of the same histogram: no edge in contrast, and the
// level of detail is each projection's own.
const int kMaxLayers = 8;
const float kDetailContrast = 0.6;
const float kCliff = 0.7071;  // cos 45 degrees
// LAYER_COUNT (1..kMaxLayers) is defined by the renderer: a loop of constant length, unrolled.
uniform sampler2DArray uDetail;
uniform vec4 uLayerMaterialMask[kMaxLayers];  // which material a layer belongs to, as a one-hot vec4
uniform float uLayerScale[kMaxLayers];        // 1 / metres per repeat
uniform float uLayerMean[kMaxLayers];         // the layer's mean gray
// Repeats to lattice coordinates (DetailLayers.cpp, kLatticeFromRepeats): the triangle lattice's vertices are the
// integer points, and each cell of the unit square holds two of its triangles.
uniform mat2 uLatticeFromRepeats;
// Per layer k, the camera's place on the vertical planes in the layer's repeats (fraction, xy) and lattice
// coordinates (reduced, zw), as LAYER_ORIGIN gives a node's: [2k] on the x-z plane, [2k + 1] on the y-z plane
// (DetailLayers::setCameraUniforms). The cliffs' coordinates count from the camera.
uniform vec4 uCliffOrigin[2 * kMaxLayers];

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

// The level of detail of layer k's texture where the projection's coordinates, in metres, change by dx and dy from
// one pixel to the next (the hardware's rule; the fetches' own derivatives would not be the footprint's, since
// their offsets jump between the lattice's triangles).
float detailLevel(int k, vec2 dx, vec2 dy)
{
    vec2 footprint = vec2(textureSize(uDetail, 0).xy) * uLayerScale[k];
    dx *= footprint;
    dy *= footprint;
    return 0.5 * log2(max(max(dot(dx, dx), dot(dy, dy)), 1e-8));
}

// Layer k at `uv` (repeats, the texture's coordinates) and `lattice` (the same point in lattice coordinates), at
// level of detail `lod`, minus its mean: the histogram-preserving blend of the three lattice vertices around it.
float tiledDetail(int k, vec2 uv, vec2 lattice, float lod)
{
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

// The factor over the colour at `local` metres from the layers' origin and `relative` metres from the camera,
// with material weights `materials` and unit normal `n`.
float detailFactor(vec2 local, vec3 relative, vec4 materials, vec3 n)
{
    float distance = length(relative);
    // The projection: onto the ground, or on a cliff onto the vertical plane the normal faces most (y-z where it
    // points along x): the point in metres from where the projection counts, and its change a pixel, each plane's
    // own (taken here, where every fragment of a quad runs: the selected point jumps where the plane changes).
    bool cliff = n.z < kCliff;
    bool facingX = abs(n.x) > abs(n.y);
    vec3 relativeDx = dFdx(relative), relativeDy = dFdy(relative);
    vec2 point = cliff ? (facingX ? relative.yz : relative.xz) : local;
    vec2 pointDx = cliff ? (facingX ? relativeDx.yz : relativeDx.xz) : dFdx(local);
    vec2 pointDy = cliff ? (facingX ? relativeDy.yz : relativeDy.xz) : dFdy(local);
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
            vec4 origin = cliff ? (facingX ? uCliffOrigin[2 * k + 1] : uCliffOrigin[2 * k]) : LAYER_ORIGIN(k);
            vec2 p = point * scale;
            // Twice the deviation from the mean, the contrast two independent samples of the tile had.
            float g = 2.0 * tiledDetail(k, origin.xy + p, origin.zw + uLatticeFromRepeats * p,
                                        detailLevel(k, pointDx, pointDy));
            layers *= vec4(1.0) + uLayerMaterialMask[k] * (amount * g);
        }
    }
    float total = dot(materials, vec4(1.0));
    return total > 0.0 ? dot(materials, layers) / total : 1.0;
}
