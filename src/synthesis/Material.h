// Materials (paper 3.4.5): a displacement function plus detail texture(s) and a ground colour, read from
// `materials/*.mat` (`option = value`, core/ConfigFile.h). Going past the paper, which blends no materials, a
// MaterialSet places several materials by slope, height, curvature and a macro variation,
// blended by the height of their own displacement where they meet, continuous everywhere so the surface has no
// seam where materials meet; the same weights colour the nodes (MaterialSet::cover). Keys: materials/README.md.
#pragma once

#include "core/ConfigFile.h"
#include "core/Expected.h"
#include "synthesis/Fractal.h"
#include "synthesis/PerlinNoise.h"

#include <array>
#include <filesystem>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace terrain {

/// A sample as placement sees it: the placement fields (DetailSynthesizer::displace: the same at a point
/// whatever the node) and the sample's world position.
struct PlacementSample {
    double slopeDegrees = 0.0;  ///< 0 flat, 90 vertical
    double height = 0.0;        ///< metres
    double curvature = 0.0;     ///< placementCurvature: degrees, > 0 in hollows, < 0 on ridges
    double x = 0.0;             ///< world metres
    double y = 0.0;
};

/// The bend of a height field at a sample, in degrees: atan of the mean change of slope over one sample
/// `spacing` along x and y, (z(W) + z(E) + z(S) + z(N) - 4 z) / (2 spacing). Positive in hollows (the surface
/// bends up), negative on ridges; 0 on any plane. Measured on the placement level's samples, so it describes
/// the relief at that spacing.
double placementCurvature(double west, double east, double south, double north, double centre, double spacing);

/// Where a material lies: full coverage for slope in [slopeMin, slopeMax] degrees, height in [heightMin,
/// heightMax] metres and curvature in [curvatureMin, curvatureMax] degrees, each rule falling smoothly
/// (smoothstep) to 0 over its blend outside its range. Blend widths are > 0 so coverage is continuous. With a
/// macro variation every rule's edges (not the ends of slope's and curvature's domains) move by
/// `variationAmount` blend widths times a smooth noise of unit deviation and `variationWavelength` metres
/// (clamped to 3 deviations), outwards or inwards, so boundaries such as a snow line wander and form patches
/// near them; ground deeper inside the range than 3 amounts of blend stays covered.
struct MaterialPlacement {
    double slopeMin = 0.0;
    double slopeMax = 90.0;
    double slopeBlend = 5.0;
    double heightMin = -std::numeric_limits<double>::infinity();
    double heightMax = std::numeric_limits<double>::infinity();
    double heightBlend = 10.0;
    double curvatureMin = -90.0;
    double curvatureMax = 90.0;
    double curvatureBlend = 1.0;
    double variationAmount = 0.0;  ///< blend widths; 0: no variation
    double variationWavelength = 500.0;
    PerlinNoise variationNoise{0};  ///< keyed by the material's seed when it is read

    /// Coverage in [0, 1] at `sample`; continuous everywhere, C1 without variation.
    double coverage(const PlacementSample& sample) const;
    /// The same at slope and height, curvature 0, at the origin.
    double coverage(double slopeDegrees, double height) const
    {
        return coverage({slopeDegrees, height, 0.0, 0.0, 0.0});
    }
    /// The variation's noise at world (x, y), of unit deviation, in [-3, 3]; 0 without variation.
    double variation(double x, double y) const;
};

enum class DisplacementKind { None, Fbm, Ridged, BitmapFbm, BitmapRidged };

struct Material {
    std::string name;  ///< `name`, or the file's stem
    std::string file;  ///< where it was read from, for messages
    DisplacementKind kind = DisplacementKind::None;
    FractalParams fractal;                              ///< the displacement's parameters (type set from kind)
    std::filesystem::path bitmap;                       ///< bitmap-* kinds: the gray tileable basis PNG (absolute)
    std::vector<std::filesystem::path> detailTextures;  ///< resolved against the .mat file's directory
    double detailTextureSize = 4.0;                     ///< metres covered by one repeat of a detail texture, > 0
    std::array<float, 3> tint = {1.0f, 1.0f, 1.0f};     ///< RGB multiplier, each in [0, 1] (MaterialSet::cover)
    std::array<float, 3> colour = {1.0f, 1.0f, 1.0f};   ///< the material's own ground colour, RGB in [0, 1]
    double colourCover = 0.0;  ///< [0, 1]: how far `colour` replaces the map's (snow: most of it; rock: none)
    /// metres, 0: off. Where this material meets the ones below it, the one whose own displacement stands
    /// higher shows: coverage c becomes clamp(c + 4 c (1 - c) (d - d_below) / blendHeight), so the transition
    /// follows the relief of the two within about +-blendHeight / 2 and coverage 0 and 1 stay as they are. It
    /// shapes where the material shows (colours, detail layers), not the surface: the displacement's weights
    /// stay smooth functions of the placement fields, which the synthesized levels' error bounds rely on.
    double blendHeight = 0.0;
    MaterialPlacement placement;
    std::shared_ptr<const Fractal> displacement;    ///< null for kind None (zero displacement)
    std::shared_ptr<const BasisTable> bitmapTable;  ///< bitmap-* kinds: the basis (relativeTo rebuilds with it)
    /// relative_amplitude: > 0, over a map with roughness laws the displacement's size follows the
    /// terrain's own roughness at each place: it is scaled so that its RMS midpoint deviation at a lag of
    /// its wavelength is relativeAmplitude times the law's there (DetailSynthesizer::materialScales), and its
    /// octaves as coarse as the data's spacing are left out (relativeTo). 0: absolute, `amplitude` metres
    /// (also what a relative material falls back to over a map without laws).
    double relativeAmplitude = 0.0;
    /// The fractal's own RMS midpoint deviation at a lag of its wavelength, metres (measured when the
    /// material is read, over 4096 places along x and y); 0 for kind None or absolute materials.
    double fractalDeviation = 0.0;

    /// The material's displacement in metres at world (x, y) metres (0 for kind None).
    double displacementAt(double x, double y) const { return displacement ? (*displacement)(x, y) : 0.0; }
};

/// Reads a material from parsed `config`: relative paths resolve against config.directory(). Unknown
/// keys append "file:line: unknown material option 'k' ignored" to `warnings`; an invalid or missing
/// value returns an error "file:line: ..." naming the key, what was expected and what was found. Reads the
/// bitmap of bitmap-* kinds and checks that detail textures exist.
Expected<Material> parseMaterial(const ConfigFile& config, std::vector<std::string>& warnings);
/// loadMaterial(path) = ConfigFile::load(path) then parseMaterial.
Expected<Material> loadMaterial(const std::filesystem::path& path, std::vector<std::string>& warnings);

/// The RMS midpoint deviation of `fractal` at a lag of its wavelength: (f(p) - (f(p - r) + f(p + r)) / 2) at
/// 4096 pseudo-random places, along x and along y (deterministic), metres.
double fractalMidpointDeviation(const Fractal& fractal);

/// `material` as synthesis uses it over data of spacing `dataSpacing` with roughness laws: a relative material
/// without the octaves whose wavelength is at least the data's spacing (the data has that relief; the
/// remaining ones start at octave 0 with the next wavelength, and the fallback amplitude shrinks by the
/// gain per octave left out), its fractalDeviation measured again; with none left it has no displacement.
/// Absolute materials are returned as they are.
Material relativeTo(const Material& material, double dataSpacing);

/// Several materials over the terrain. Material 0 is the ground everywhere; each later material is laid
/// over the ones before it with its placement coverage c_m, so weight_m = c_m * prod_{k > m} (1 - c_k)
/// (c_0 = 1). The weights are continuous, in [0, 1] and sum to 1 (up to rounding), whatever the rules.
class MaterialSet {
public:
    /// Precondition: at least one material.
    explicit MaterialSet(std::vector<Material> materials);
    /// Loads each file in order (the first is the ground); the first error stops.
    static Expected<MaterialSet> load(const std::vector<std::filesystem::path>& files,
                                      std::vector<std::string>& warnings);

    const std::vector<Material>& materials() const { return mMaterials; }
    /// relativeTo() of every material.
    MaterialSet relativeTo(double dataSpacing) const;
    /// Whether any material has a relative amplitude.
    bool hasRelative() const;

    /// Blend weights at `sample` into out[0 .. materials().size()). `displacements`: each material's own
    /// displacement there (metres, as blended: scaled where relative), for the height blending of materials
    /// with a blendHeight (the weights the ground shows); empty: no height blending (the weights the
    /// displacement blends with). Precondition: out.size() >= materials().size(), and displacements empty or as
    /// large.
    void weights(const PlacementSample& sample, std::span<const double> displacements, std::span<double> out) const;
    /// The same at slope and height, curvature 0, at the origin, without height blending.
    void weights(double slopeDegrees, double height, std::span<double> out) const
    {
        weights({slopeDegrees, height, 0.0, 0.0, 0.0}, {}, out);
    }
    /// Whether any material blends by its height (weights then need the displacements).
    bool blendsByHeight() const;
    /// Whether any material is placed by curvature.
    bool usesCurvature() const;

    /// Blended displacement at `sample`: sum_m weight_m * float(material_m displacement), in metres, with the
    /// weights without height blending. The
    /// placement fields should come from the base height field (the same in every node), so the blend, like
    /// the displacement, depends only on the position.
    float displacement(const PlacementSample& sample) const;
    float displacement(double x, double y, double slopeDegrees, double height) const
    {
        return displacement({slopeDegrees, height, 0.0, x, y});
    }

    /// The ground colour of the map's colour `rgb` (each in [0, 1]) under the materials with `weights`:
    /// sum_m weight_m * mix(rgb * tint'_m, colour_m, colourCover_m), where tint'_m is a third of the tint at the
    /// map colour's brightness (the map's colours stay the base: a grass tint does not paint a dry valley green).
    std::array<float, 3> cover(const std::array<float, 3>& rgb, std::span<const double> weights) const;
    /// Material m's part of cover() as a linear map of the map's colour: mix(rgb * tint'_m, colour_m,
    /// colourCover_m) = rgb * scale + offset, per channel.
    struct CoverTerms {
        std::array<double, 3> scale;
        std::array<double, 3> offset;
    };
    CoverTerms coverTerms(std::size_t m) const;

    /// The grid form: out[k] = displacement({slope[k], height[k], curvature[k], grid.x(i), grid.y(j)}) with
    /// k = j * width + i, bit-identical to the point form; a material whose weight is zero over the whole
    /// window is not evaluated. `curvature` empty: 0 everywhere. With a non-empty `mask` only samples with
    /// mask[k] != 0 are computed and written. With `scales`, material m's displacement is multiplied by
    /// scales[m][k] where that is not empty (the relative materials' DetailSynthesizer::materialScales). With
    /// `weightsOut` (count * materials().size() bytes), each computed sample's weights as the ground shows them
    /// (height-blended with the displacements evaluated here), in 1/255 steps.
    /// Preconditions: as Fractal::evaluateGrid; slope and height hold grid.count() values, scales is empty or
    /// has one entry per material.
    void displacementGrid(const SampleGrid& grid, std::span<const float> slopeDegrees, std::span<const float> heights,
                          std::span<float> out, std::span<const std::uint8_t> mask = {},
                          std::span<const std::vector<float>> scales = {}, std::span<const float> curvature = {},
                          std::span<std::uint8_t> weightsOut = {}) const;

private:
    std::vector<Material> mMaterials;
};

}  // namespace terrain
