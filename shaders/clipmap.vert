#version 330 core
// Geometry clipmap vertex program (seed 002, GPU Gems 2 chapter 2; render/ClipmapRenderer.h): a footprint's
// grid vertex becomes a sample of its ring's window, its height fetched from the ring's toroidal elevation
// layer and blended towards the next coarser ring's surface (bilinear there) by the transition weight
// alpha = clamp((max |p - viewer| - ((n - 1) / 2 - w - 1)) / w, 0, 1), the same for its normal, so the
// perimeter of a ring lies exactly on the coarser ring and nothing cracks or pops as the viewer moves.
// Samples that change in view (a node arriving where its samples were upsampled) morph over uMorphSeconds
// from the height drawn before (uMorph: previous height, time of the change; ClipmapTerrain::drawnSample is the
// same in C++), and the fragment program blends their colours, material weights and normals the same way; the
// sky's visibility is blended and morphed here, per vertex, as the quadtree's vertices do (shaders/surface.glsl).

layout(location = GRID_LOCATION) in ivec2 aGrid;  // the vertex, cells from its footprint's corner

uniform mat4 uViewProjection;    // camera-relative world -> clip
uniform sampler2DArray uHeights; // per ring: n x n metres above the map's offset, texel = sample mod n
uniform sampler2DArray uMorph;   // per ring, the same texels: (height drawn before the change, its time in s)
uniform sampler2DArray uSkyVisibility;  // per ring, the same texels: the sky's visibility, and before the change
uniform float uNow;              // the clipmap's clock (ClipmapTerrain::clock), seconds
uniform float uMorphSeconds;     // > 0 (0 morphs are passed as a tiny time: every change is over)
uniform int uSamples;            // n
uniform int uRing;               // this ring's layer
uniform int uHasCoarser;         // 0 for the coarsest ring (nothing to blend to)
uniform ivec2 uPieceOrigin;      // the footprint's corner, cells from the window origin
uniform ivec2 uWindowTexel;      // the window origin's texel
uniform ivec2 uCoarseTexel;      // the coarser window's origin texel
uniform ivec2 uCoarseOffset;     // this window's origin in the coarser window, its cells
uniform vec2 uWindowOffset;      // the window origin minus the camera, metres (x, y)
uniform float uSpacing;          // metres between this ring's samples
uniform float uHeightBase;       // the map's height offset minus the camera's height, metres
uniform vec2 uViewer;            // the viewer in this ring's samples from the window origin
uniform float uBlendStart;       // (n - 1) / 2 - w - 1
uniform float uBlendWidth;       // w

out vec3 vRelative;
out vec3 vNormal;
out vec2 vFineUv;
out vec2 vCoarseUv;
out float vBlend;
out float vRemaining;        // of this vertex's morph
out float vCoarseRemaining;  // of the coarser ring's at this vertex (bilinear, as its height)
out float vSkyVisibility;    // the share of the sky the terrain around leaves the vertex, morphed and blended
out vec2 vLocal;  // metres from the window origin (the detail layers count from there)
#ifdef NORMAL_MAP
uniform float uNormalTexelsPerCell;  // r: the normal layers have r n texels a side, sample g at texel r g
out vec2 vNormalUv;
out vec2 vCoarseNormalUv;
#endif

// How far a sample's morph has gone (0 when it has just changed, 1 once it is over).
float done(ivec3 texel)
{
    return clamp((uNow - texelFetch(uMorph, texel, 0).g) / uMorphSeconds, 0.0, 1.0);
}

// How much of it is still to come.
float remaining(ivec3 texel)
{
    return 1.0 - done(texel);
}

// A sample as drawn now: its height, or on its way there from the height drawn before (exactly the height once
// the morph is over; ClipmapTerrain::drawnSample).
float drawn(ivec3 texel)
{
    float previous = texelFetch(uMorph, texel, 0).r;
    float height = texelFetch(uHeights, texel, 0).r;
    float d = done(texel);
    return d >= 1.0 ? height : previous + (height - previous) * d;
}

ivec3 fineTexel(ivec2 local)
{
    ivec2 p = clamp(local, ivec2(0), ivec2(uSamples - 1));
    return ivec3((uWindowTexel + p) % uSamples, uRing);
}

float fine(ivec2 local)
{
    return drawn(fineTexel(local));
}

ivec3 coarseTexel(ivec2 c)
{
    return ivec3((uCoarseTexel + clamp(c, ivec2(0), ivec2(uSamples - 1))) % uSamples, uRing + 1);
}

float coarseAt(ivec2 c)
{
    return drawn(coarseTexel(c));
}

// A sample's sky visibility as drawn now: on its way from what it was drawn as before its change.
float drawnSky(ivec3 texel)
{
    vec2 sky = texelFetch(uSkyVisibility, texel, 0).rg;
    return mix(sky.r, sky.g, remaining(texel));
}

// The coarser ring's remaining morph (x) and drawn sky visibility (y) at this ring's sample `local`, bilinear
// like its surface.
vec2 coarseRemainingAndSky(ivec2 local)
{
    ivec2 c = uCoarseOffset + (local >> 1);
    vec2 f = 0.5 * vec2(local & 1);
    ivec3 t00 = coarseTexel(c), t10 = coarseTexel(c + ivec2(1, 0)), t01 = coarseTexel(c + ivec2(0, 1)),
          t11 = coarseTexel(c + ivec2(1, 1));
    return mix(mix(vec2(remaining(t00), drawnSky(t00)), vec2(remaining(t10), drawnSky(t10)), f.x),
               mix(vec2(remaining(t01), drawnSky(t01)), vec2(remaining(t11), drawnSky(t11)), f.x), f.y);
}

// The coarser ring's surface at this ring's sample `local` (bilinear: exact at even samples, the mean of two
// or four at odd ones), and its gradient (metres per metre) from its cell.
float coarse(ivec2 local, out vec2 gradient)
{
    ivec2 c = uCoarseOffset + (local >> 1);
    ivec2 odd = local & 1;
    float h00 = coarseAt(c), h10 = coarseAt(c + ivec2(1, 0)), h01 = coarseAt(c + ivec2(0, 1)),
          h11 = coarseAt(c + ivec2(1, 1));
    vec2 f = 0.5 * vec2(odd);
    gradient = vec2(mix(h10 - h00, h11 - h01, f.y), mix(h01 - h00, h11 - h10, f.x)) / (2.0 * uSpacing);
    return mix(mix(h00, h10, f.x), mix(h01, h11, f.x), f.y);
}

void main()
{
    ivec2 local = uPieceOrigin + aGrid;
    float own = fine(local);
    vec2 ownGradient = vec2(fine(local + ivec2(1, 0)) - fine(local - ivec2(1, 0)),
                            fine(local + ivec2(0, 1)) - fine(local - ivec2(0, 1))) / (2.0 * uSpacing);
    float alpha = 0.0;
    float height = own;
    vec2 gradient = ownGradient;
    if (uHasCoarser != 0) {
        vec2 d = abs(vec2(local) - uViewer);
        alpha = clamp((max(d.x, d.y) - uBlendStart) / uBlendWidth, 0.0, 1.0);
        vec2 coarseGradient;
        float below = coarse(local, coarseGradient);
        height = mix(own, below, alpha);
        gradient = mix(ownGradient, coarseGradient, alpha);
    }
    vNormal = normalize(vec3(-gradient, 1.0));
    vRelative = vec3(uWindowOffset + vec2(local) * uSpacing, uHeightBase + height);
    vFineUv = (vec2(uWindowTexel + local) + 0.5) / float(uSamples);
    vCoarseUv = (vec2(uCoarseTexel + uCoarseOffset) + 0.5 * vec2(local) + 0.5) / float(uSamples);
    vBlend = alpha;
    vRemaining = remaining(fineTexel(local));
    vSkyVisibility = drawnSky(fineTexel(local));
    vCoarseRemaining = 0.0;
    if (uHasCoarser != 0) {
        vec2 coarser = coarseRemainingAndSky(local);
        vCoarseRemaining = coarser.x;
        vSkyVisibility = mix(vSkyVisibility, coarser.y, alpha);
    }
    vLocal = vec2(local) * uSpacing;
#ifdef NORMAL_MAP
    float side = uNormalTexelsPerCell * float(uSamples);
    vNormalUv = (uNormalTexelsPerCell * vec2(uWindowTexel + local) + 0.5) / side;
    vCoarseNormalUv = (uNormalTexelsPerCell * (vec2(uCoarseTexel + uCoarseOffset) + 0.5 * vec2(local)) + 0.5) / side;
#endif
    gl_Position = uViewProjection * vec4(vRelative, 1.0);
}
