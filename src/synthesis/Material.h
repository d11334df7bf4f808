// Materials (paper 3.4.5): a displacement function plus detail texture(s) and a tint, read from
// `materials/*.mat` (`option = value`, core/ConfigFile.h). Going past the paper ("multiple materials are
// not implemented"), a MaterialSet places several materials by slope and height with smooth blending,
// continuous everywhere so the surface has no seam where materials meet. Keys: materials/README.md.
#pragma once

#include "core/ConfigFile.h"
#include "core/Expected.h"
#include "synthesis/Fractal.h"

#include <array>
#include <filesystem>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace terrain {

/// Where a material lies: full coverage for slope in [slopeMin, slopeMax] degrees and height in
/// [heightMin, heightMax] metres, falling smoothly (smoothstep) to 0 over slopeBlend degrees and
/// heightBlend metres outside those ranges. Blend widths are > 0 so coverage is continuous.
struct MaterialPlacement {
    double slopeMin = 0.0;
    double slopeMax = 90.0;
    double slopeBlend = 5.0;
    double heightMin = -std::numeric_limits<double>::infinity();
    double heightMax = std::numeric_limits<double>::infinity();
    double heightBlend = 10.0;

    /// Coverage in [0, 1] at `slopeDegrees` (0 flat, 90 vertical) and `height` metres; C1 in both.
    double coverage(double slopeDegrees, double height) const;
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
    std::array<float, 3> tint = {1.0f, 1.0f, 1.0f};     ///< linear RGB multiplier, each in [0, 1]
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

    /// Blend weights at `slopeDegrees` and `height` metres into out[0 .. materials().size()).
    /// Precondition: out.size() >= materials().size().
    void weights(double slopeDegrees, double height, std::span<double> out) const;

    /// Blended displacement at world (x, y): sum_m weight_m * float(material_m displacement), in metres.
    /// Slope and height should come from the base height field (the same in every node), so the
    /// blend, like the displacement, depends only on the position.
    float displacement(double x, double y, double slopeDegrees, double height) const;

    /// The grid form: out[k] = displacement(grid.x(i), grid.y(j), slope[k], height[k]) with
    /// k = j * width + i, bit-identical to the point form; a material whose weight is zero over the whole
    /// window is not evaluated. With a non-empty `mask` only samples with mask[k] != 0 are computed and
    /// written. With `scales`, material m's displacement is multiplied by scales[m][k] where that is not empty
    /// (the relative materials' DetailSynthesizer::materialScales). Preconditions: as Fractal::evaluateGrid;
    /// slope and height hold grid.count() values, scales is empty or has one entry per material.
    void displacementGrid(const SampleGrid& grid, std::span<const float> slopeDegrees, std::span<const float> heights,
                          std::span<float> out, std::span<const std::uint8_t> mask = {},
                          std::span<const std::vector<float>> scales = {}) const;

private:
    std::vector<Material> mMaterials;
};

}  // namespace terrain
