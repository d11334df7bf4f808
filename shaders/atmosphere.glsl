// The air between the viewer, the terrain and the sun, in float: Rayleigh and Mie scattering (once, and more often as
// Hillaire's psi_ms) in an
// exponential atmosphere over a flat ground, HDR radiance relative to the sun's irradiance above the air, and the
// filmic tone map. The same model as src/light/Atmosphere.h, its reference (AtmosphereGLTest compares them);
// read the equations there. The sums (inscatter) reuse each sample's densities for its sunlight, and the sun's
// air mass comes once a frame. They fill the frame's tables (shaders/atmosphere_table.frag, compiled with
// ATMOSPHERE_TABLE; light/AtmosphereTables.h gives their layout), which the terrain and the sky read in one
// fetch a pixel (aerialPerspective, skyRadiance). The tables' sizes and sample counts come from the C++/GLSL
// contract, the constants from AtmosphereModel through these uniforms (FrameSetup.cpp sets them).

uniform vec3 uRayleighScattering;  // per metre at sea level
uniform float uRayleighHeight;     // scale height, metres
uniform float uMieScattering;
uniform float uMieExtinction;
uniform float uMieHeight;
uniform float uMieAnisotropy;
uniform float uTopScaleHeights;
uniform float uCameraAltitude;  // metres (world z)
uniform vec2 uCameraDensities;  // the Rayleigh and Mie densities at the camera, exp(-altitude / scale height)
uniform float uExposure;
uniform float uSunAirMass;  // airMass() of the sun's elevation, per frame
// psi_ms (light/Atmosphere.h, multipleScattering) at altitudes top (i / (n - 1))^2, for the frame's sun, and the
// sky's irradiance on a horizontal surface at the same altitudes (MultipleScattering::irradiance).
uniform vec3 uMultipleScattering[MULTIPLE_SCATTERING_ALTITUDES];
uniform vec3 uSkyIrradiance[MULTIPLE_SCATTERING_ALTITUDES];
uniform float uMultipleScatteringTop;

const float kPi = 3.14159265358979;

// The view ray to a point `rise` metres above the camera and `len` metres from it: its optical depths (Rayleigh,
// Mie; metres at sea-level density) and the densities at the point (exp(-altitude / scale height)). Two
// exponentials, with the camera's densities a uniform: what the terrain's vertex programs compute for every
// vertex (airAt). The depth is len times the mean density along the ray, (camera's - point's) / (rise / scale
// height), its series near rise 0; exact from the ground to orbit (the camera's densities may underflow to 0).
void viewRay(float rise, float len, out vec2 depth, out vec2 density)
{
    vec2 heights = vec2(uRayleighHeight, uMieHeight);
    vec2 x = rise / heights;
    density = exp(-(uCameraAltitude + rise) / heights);
    vec2 series = uCameraDensities * (1.0 - x * (0.5 - x / 6.0));
    vec2 mean = vec2(abs(x.x) < 1e-2 ? series.x : (uCameraDensities.x - density.x) / x.x,
                     abs(x.y) < 1e-2 ? series.y : (uCameraDensities.y - density.y) / x.y);
    depth = len * mean;
}

// The transmittance of a ray of optical depths `depth` (viewRay).
vec3 transmittanceOf(vec2 depth)
{
    return exp(-(uRayleighScattering * depth.x + vec3(uMieExtinction * depth.y)));
}

float airMass(float elevation)
{
    float degrees = max(elevation, 0.0) * (180.0 / kPi);
    return 1.0 / (sin(degrees * (kPi / 180.0)) + 0.50572 * pow(degrees + 6.07995, -1.6364));
}

// Of sunlight at a point where the Rayleigh and Mie densities are `rayleighDensity` and `mieDensity`
// (exp(-altitude / scale height)).
vec3 sunTransmittanceAt(float rayleighDensity, float mieDensity)
{
    return exp(-(uRayleighScattering * (uRayleighHeight * rayleighDensity) +
                 vec3(uMieExtinction * uMieHeight * mieDensity)) *
               uSunAirMass);
}

vec3 sunTransmittance(float altitude)
{
    return sunTransmittanceAt(exp(-altitude / uRayleighHeight), exp(-altitude / uMieHeight));
}

float rayleighPhase(float mu)
{
    return 3.0 / (16.0 * kPi) * (1.0 + mu * mu);
}

float miePhase(float mu, float g)
{
    float g2 = g * g;
    return 3.0 / (8.0 * kPi) * (1.0 - g2) * (1.0 + mu * mu) / ((2.0 + g2) * pow(1.0 + g2 - 2.0 * g * mu, 1.5));
}

// The altitudes held below and above `altitude` metres: the lower one's index, and in `weight` the upper one's
// share (the ground's below 0 and for NaN, the top's above; MultipleScattering::at).
int altitudeCell(float altitude, out float weight)
{
    const int n = MULTIPLE_SCATTERING_ALTITUDES;
    float share = altitude / uMultipleScatteringTop;
    float x = sqrt(share >= 0.0 ? min(share, 1.0) : 0.0) * float(n - 1);  // NaN reads the ground's
    int i = clamp(int(x), 0, n - 2);
    weight = x - float(i);
    return i;
}

// psi_ms at `altitude` metres, linear between the altitudes held (MultipleScattering::at).
vec3 multipleScatteringAt(float altitude)
{
    if (!(uMultipleScatteringTop > 0.0)) {
        return vec3(0.0);  // not set: single scattering
    }
    float weight;
    int i = altitudeCell(altitude, weight);
    return mix(uMultipleScattering[i], uMultipleScattering[i + 1], weight);
}

// The sky's irradiance on a horizontal surface at `altitude` metres (MultipleScattering::irradianceAt); none
// where the frame's uniforms are not set.
vec3 skyIrradianceAt(float altitude)
{
    if (!(uMultipleScatteringTop > 0.0)) {
        return vec3(0.0);
    }
    float weight;
    int i = altitudeCell(altitude, weight);
    return mix(uSkyIrradiance[i], uSkyIrradiance[i + 1], weight);
}

// The in-scattered light of a segment from `altitude`, `len` metres rising `slope` a metre, at cos(view, sun)
// `mu`: midpoints of u in [0, 1], t = len u^2.
vec3 inscatter(float altitude, float slope, float len, float mu, int samples)
{
    float rayleighPhaseValue = rayleighPhase(mu);
    float miePhaseValue = miePhase(mu, uMieAnisotropy);
    // The densities where the segment starts: the densities along it are these times exp(-rise / H).
    float rayleighStart = exp(-altitude / uRayleighHeight);
    float mieStart = exp(-altitude / uMieHeight);
    vec3 sum = vec3(0.0);
    for (int k = 0; k < samples; ++k) {
        float u = (float(k) + 0.5) / float(samples);
        float t = len * u * u;
        float rise = slope * t;
        float rayleighFall = exp(-rise / uRayleighHeight);
        float mieFall = exp(-rise / uMieHeight);
        // The view ray's optical depth to t (densityIntegral with the falls already taken).
        float rayleighDepth = rayleighStart * t * (abs(rise) < 1e-2 * uRayleighHeight
                                                        ? 1.0 - rise / uRayleighHeight * (0.5 - rise / (6.0 * uRayleighHeight))
                                                        : (1.0 - rayleighFall) * uRayleighHeight / rise);
        float mieDepth = mieStart * t * (abs(rise) < 1e-2 * uMieHeight
                                              ? 1.0 - rise / uMieHeight * (0.5 - rise / (6.0 * uMieHeight))
                                              : (1.0 - mieFall) * uMieHeight / rise);
        vec3 toSample = exp(-(uRayleighScattering * rayleighDepth + vec3(uMieExtinction * mieDepth)));
        float rayleighDensity = rayleighStart * rayleighFall, mieDensity = mieStart * mieFall;
        vec3 scattering = uRayleighScattering * (rayleighDensity * rayleighPhaseValue) +
                          vec3(uMieScattering * mieDensity * miePhaseValue);
        // Scattered once, from the sun; more than once, psi_ms times the scattering coefficient.
        vec3 light = scattering * sunTransmittanceAt(rayleighDensity, mieDensity) +
                     (uRayleighScattering * rayleighDensity + vec3(uMieScattering * mieDensity)) *
                         multipleScatteringAt(altitude + rise);
        sum += toSample * light * (2.0 * len * u);
    }
    return sum / float(samples);
}

// The view direction at table coordinates `c` (light/AtmosphereTables.h, directionAt): azimuth 4 atan(c.x^2) from
// the sun's, elevation 2 atan((2 c.y - 1)^2) signed, spaced finely at the horizon.
vec3 tableDirection(vec2 c, vec3 sun)
{
    float sunAzimuth = sun.x == 0.0 && sun.y == 0.0 ? 0.0 : atan(sun.y, sun.x);
    float azimuth = sunAzimuth - 4.0 * atan(clamp(c.x * c.x, 0.0, 1.0));
    float e = 2.0 * c.y - 1.0;
    float t = min(e * e, 1.0);  // tan(|elevation| / 2)
    float z = 2.0 * t / (1.0 + t * t);
    return vec3((1.0 - t * t) / (1.0 + t * t) * vec2(cos(azimuth), sin(azimuth)), e < 0.0 ? -z : z);
}

// The table coordinates of view direction `view` of any length > 0 (directionCoordinate) with the sun in unit
// direction `sun`: no inverse trigonometric function, for a vertex program's lookup. tan(azimuth / 4) from the
// horizontal unit directions a and b is |a - b| / (2 + |a + b|) (0 where either is vertical), tan(|elevation| / 2)
// is |z| / (length + horizontal length).
vec2 tableCoordinate(vec3 view, vec3 sun)
{
    float viewHorizontal = dot(view.xy, view.xy), sunHorizontal = dot(sun.xy, sun.xy);
    float azimuthTangent = 0.0;
    if (viewHorizontal > 0.0 && sunHorizontal > 0.0) {
        vec2 a = view.xy * inversesqrt(viewHorizontal), b = sun.xy * inversesqrt(sunHorizontal);
        azimuthTangent = length(a - b) / (2.0 + length(a + b));
    }
    float horizontal = sqrt(viewHorizontal);
    float len = sqrt(viewHorizontal + view.z * view.z);
    float e = len > 0.0 ? sqrt(min(abs(view.z) / (len + horizontal), 1.0)) : 0.0;
    return vec2(sqrt(min(azimuthTangent, 1.0)), 0.5 + 0.5 * (view.z < 0.0 ? -e : e));
}

// A coordinate in [0, 1] as the texture coordinate of a table `cells` long whose first and last cells are its ends.
vec2 onCells(vec2 c, vec2 cells) { return (c * (cells - 1.0) + 0.5) / cells; }

// What a table cell holds: the in-scattered light of the segment `distance` metres along `view`, and the sky's.
vec3 aerialSum(vec3 view, float distance, vec3 sun)
{
    return inscatter(uCameraAltitude, view.z, distance, dot(view, sun), AERIAL_TABLE_SAMPLES);
}

vec3 skySum(vec3 view, vec3 sun)
{
    float elevation = asin(clamp(view.z, -1.0, 1.0));
    float slope = 1.0 / airMass(elevation);
    float len = uTopScaleHeights * uRayleighHeight / slope;
    return inscatter(uCameraAltitude, slope, len, dot(view, sun), SKY_TABLE_SAMPLES);
}

#ifndef ATMOSPHERE_TABLE
// The frame's tables (render/AtmosphereTables.h): the aerial table's light per unit of (distance / range) over
// azimuth, elevation and sqrt(distance / range); the sky's radiance over azimuth and elevation.
uniform sampler3D uAerialTable;
uniform sampler2D uSkyTable;
uniform float uAerialRange;  // metres the aerial table spans

// The aerial table's coordinates in [0, 1]^3 of a surface point `relative` metres from the camera, `len` metres
// away (azimuth, elevation, sqrt(distance / range)). Its azimuth folds at the sun's: what a vertex reads from the
// table interpolates over a triangle (Air), the coordinates would not.
vec3 aerialCoordinate(vec3 relative, float len, vec3 sun)
{
    if (len <= 0.0) {
        return vec3(0.0);
    }
    return vec3(tableCoordinate(relative, sun), sqrt(min(len / uAerialRange, 1.0)));
}

// The light the air scatters in between the camera and the point at aerial coordinates `c` (one fetch).
vec3 aerialInscattered(vec3 c)
{
    vec3 cells = vec3(AERIAL_TABLE_AZIMUTHS, AERIAL_TABLE_ELEVATIONS, AERIAL_TABLE_DISTANCES);
    return texture(uAerialTable, (c * (cells - 1.0) + 0.5) / cells).rgb * (c.z * c.z);
}

// What the air does to a surface point `relative` metres from the camera: the sunlight that reaches it
// (sunTransmittance), the transmittance of the view ray, and the light the air scatters in along it (one fetch of
// the aerial table). All three change smoothly over a triangle: the terrain's vertex programs make them per vertex
// (surface.glsl), and the fragments interpolate them, which saves a fetch of a 3D table and eight exponentials a
// pixel. (The table's coordinates would not interpolate: their azimuth folds at the sun's.)
// With them the sky's irradiance there (skyIrradianceAt: a lookup by altitude, which terrain.frag makes per pixel;
// the vertex programs leave it).
struct Air {
    vec3 sunlight;
    vec3 transmittance;
    vec3 inscattered;
    vec3 skylight;
};

Air airAt(vec3 relative, vec3 sun)
{
    float len = length(relative);
    vec2 depth, density;
    viewRay(relative.z, len, depth, density);
    return Air(sunTransmittanceAt(density.x, density.y), transmittanceOf(depth),
               aerialInscattered(aerialCoordinate(relative, len, sun)), skyIrradianceAt(uCameraAltitude + relative.z));
}

// The light of a surface point `relative` metres from the camera, `radiance` where it is, as it reaches the
// camera: times the air's transmittance, plus what the air scatters in.
vec3 aerialPerspective(vec3 radiance, vec3 relative, vec3 sun)
{
    Air air = airAt(relative, sun);
    return radiance * air.transmittance + air.inscattered;
}

// The sky's radiance in unit direction `view` (the sun's disc not included; one fetch of the sky table).
vec3 skyRadiance(vec3 view, vec3 sun)
{
    vec2 cells = vec2(SKY_TABLE_AZIMUTHS, SKY_TABLE_ELEVATIONS);
    return texture(uSkyTable, onCells(tableCoordinate(view, sun), cells)).rgb;
}
#endif

// The filmic tone map (Narkowicz's ACES fit) of the exposed radiance, then the display's gamma, 2 (a square root:
// sRGB's 2.2 costs two pow a fragment on llvmpipe, 6% of the frame, for a curve within 0.04 of it).
vec3 toneMap(vec3 radiance)
{
    vec3 x = max(radiance * uExposure, vec3(0.0));
    vec3 mapped = clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
    return sqrt(mapped);
}
