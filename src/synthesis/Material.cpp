// Materials (paper 3.4.5) and their placement by slope, height, curvature and a macro variation with smooth,
// seam-free blending, and the ground colour they give.
#include "synthesis/Material.h"

#include "core/Check.h"
#include "core/Parse.h"
#include "core/SplitMix64.h"
#include "heightfield/Image.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <numbers>

namespace terrain {

namespace {

double smoothstep(double t)
{
    t = std::clamp(t, 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

/// 1 inside [lo, hi], smoothstep down to 0 over `blend` outside. `shift` blend widths move the edges outwards
/// (inwards where negative): the ramp then reads the signed distance into the range, so ground deeper inside than
/// the shift stays covered. An edge at the end of the value's domain (`first`, `last`: slope 0 and 90) is none.
double ramp(double value, double lo, double hi, double blend, double shift = 0.0,
            double first = -std::numeric_limits<double>::infinity(),
            double last = std::numeric_limits<double>::infinity())
{
    if (shift == 0.0) {
        const double outside = value < lo ? lo - value : (value > hi ? value - hi : 0.0);
        return smoothstep(1.0 - outside / blend);
    }
    const double fromLo = lo <= first ? std::numeric_limits<double>::infinity() : value - lo;
    const double fromHi = hi >= last ? std::numeric_limits<double>::infinity() : hi - value;
    const double inside = std::min(fromLo, fromHi);  // < 0 outside
    if (inside == std::numeric_limits<double>::infinity()) {
        return 1.0;  // a rule without edges
    }
    // The shift is at most 3 x 4 blend widths: ground deeper inside than that is covered whatever the noise.
    return smoothstep(1.0 + std::min(inside / blend, 13.0) + shift);
}

/// Splits "a, b, c" at commas and parses each as a number.
Expected<std::vector<double>> parseList(std::string_view text)
{
    std::vector<double> values;
    std::size_t start = 0;
    while (true) {
        std::size_t comma = text.find(',', start);
        std::string_view part =
            text.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start);
        while (!part.empty() && (part.front() == ' ' || part.front() == '\t')) {
            part.remove_prefix(1);
        }
        while (!part.empty() && (part.back() == ' ' || part.back() == '\t')) {
            part.remove_suffix(1);
        }
        auto value = parseDouble(part);
        if (!value) {
            return value.error();
        }
        values.push_back(*value);
        if (comma == std::string_view::npos) {
            return values;
        }
        start = comma + 1;
    }
}

/// Parses "a, b, c" into three numbers in [0, 1].
Status readRgb(const ConfigEntry& entry, std::array<float, 3>& out, const std::function<Error(std::string)>& fail)
{
    auto list = parseList(entry.value);
    if (!list || list->size() != 3 ||
        std::any_of(list->begin(), list->end(), [](double c) { return !(c >= 0.0 && c <= 1.0); })) {
        return fail("expected 'r, g, b', each in [0, 1]");
    }
    for (int i = 0; i < 3; ++i) {
        out[static_cast<std::size_t>(i)] = static_cast<float>((*list)[static_cast<std::size_t>(i)]);
    }
    return {};
}

struct Reader {
    const ConfigEntry& entry;
    Material& material;
    const std::filesystem::path& directory;

    Error fail(const std::string& what) const
    {
        return makeError(entry.location(), ": ", entry.key, " = '", entry.value, "': ", what);
    }
    Expected<double> number(double lo, double hi, const char* range) const
    {
        auto value = parseDouble(entry.value);
        if (!value || *value < lo || *value > hi) {
            return fail(std::string("expected a number in ") + range);
        }
        return *value;
    }
    Expected<double> positive() const
    {
        auto value = parseDouble(entry.value);
        if (!value || !(*value > 0.0)) {
            return fail("expected a positive number");
        }
        return *value;
    }
    Expected<std::array<double, 2>> range(double lo, double hi, const char* what) const
    {
        auto list = parseList(entry.value);
        if (!list || list->size() != 2 || (*list)[0] > (*list)[1] || (*list)[0] < lo || (*list)[1] > hi) {
            return fail(std::string("expected 'min, max' with min <= max, ") + what);
        }
        return std::array<double, 2>{(*list)[0], (*list)[1]};
    }
    Expected<std::filesystem::path> existingFile() const
    {
        if (entry.value.empty()) {
            return fail("expected a file name");
        }
        std::filesystem::path path = directory / entry.value;
        std::error_code ec;  // the non-throwing form: a name too long or unreadable is an error value too
        if (!std::filesystem::is_regular_file(path, ec)) {
            return fail("no such file: " + path.string() + (ec ? " (" + ec.message() + ")" : ""));
        }
        return path;
    }
};

using Setter = std::function<Status(const Reader&)>;

template <class T>
Status assign(Expected<T> value, T& target)
{
    if (!value) {
        return value.error();
    }
    target = *value;
    return {};
}

using SetterTable = std::map<std::string, Setter, std::less<>>;

/// The keys of the displacement and the detail textures.
SetterTable displacementSetters()
{
    return {
        {"name",
         [](const Reader& r) -> Status {
             if (r.entry.value.empty()) {
                 return r.fail("expected a name");
             }
             r.material.name = r.entry.value;
             return {};
         }},
        {"displacement",
         [](const Reader& r) -> Status {
             static const std::map<std::string, DisplacementKind, std::less<>> kinds = {
                 {"none", DisplacementKind::None},
                 {"fbm", DisplacementKind::Fbm},
                 {"ridged", DisplacementKind::Ridged},
                 {"bitmap-fbm", DisplacementKind::BitmapFbm},
                 {"bitmap-ridged", DisplacementKind::BitmapRidged}};
             auto it = kinds.find(r.entry.value);
             if (it == kinds.end()) {
                 return r.fail("expected none, fbm, ridged, bitmap-fbm or bitmap-ridged");
             }
             r.material.kind = it->second;
             return {};
         }},
        {"octaves",
         [](const Reader& r) -> Status {
             auto value = parseInteger(r.entry.value);
             if (!value || *value < 1 || *value > 24) {
                 return r.fail("expected an integer in [1, 24]");
             }
             r.material.fractal.octaves = static_cast<int>(*value);
             return {};
         }},
        {"lacunarity",
         [](const Reader& r) { return assign(r.number(1.1, 8.0, "[1.1, 8]"), r.material.fractal.lacunarity); }},
        {"gain",
         [](const Reader& r) -> Status {
             auto value = parseDouble(r.entry.value);
             if (!value || !(*value > 0.0 && *value <= 1.0)) {
                 return r.fail("expected a number in (0, 1]");
             }
             r.material.fractal.gain = *value;
             return {};
         }},
        {"wavelength", [](const Reader& r) { return assign(r.positive(), r.material.fractal.wavelength); }},
        {"amplitude",
         [](const Reader& r) { return assign(r.number(0.0, 1e4, "[0, 10000] metres"), r.material.fractal.amplitude); }},
        {"relative_amplitude",
         [](const Reader& r) { return assign(r.number(1e-3, 100.0, "[0.001, 100]"), r.material.relativeAmplitude); }},
        {"seed",
         [](const Reader& r) -> Status {
             auto value = parseInteger(r.entry.value);
             if (!value || *value < 0) {
                 return r.fail("expected a non-negative integer");
             }
             r.material.fractal.seed = static_cast<std::uint64_t>(*value);
             return {};
         }},
        {"ridge_offset",
         [](const Reader& r) { return assign(r.number(0.5, 1.5, "[0.5, 1.5]"), r.material.fractal.ridgeOffset); }},
        {"ridge_feedback",
         [](const Reader& r) { return assign(r.number(0.0, 8.0, "[0, 8]"), r.material.fractal.ridgeFeedback); }},
        {"cache",
         [](const Reader& r) -> Status {
             static const std::map<std::string, FractalCache, std::less<>> caches = {
                 {"none", FractalCache::None}, {"basis", FractalCache::Basis}, {"fractal", FractalCache::Fractal}};
             auto it = caches.find(r.entry.value);
             if (it == caches.end()) {
                 return r.fail("expected none, basis or fractal");
             }
             r.material.fractal.cache = it->second;
             return {};
         }},
        {"bitmap", [](const Reader& r) { return assign(r.existingFile(), r.material.bitmap); }},
        {"detail_texture",
         [](const Reader& r) -> Status {
             auto path = r.existingFile();
             if (!path) {
                 return path.error();
             }
             r.material.detailTextures.push_back(*path);
             return {};
         }},
        {"detail_texture_size", [](const Reader& r) { return assign(r.positive(), r.material.detailTextureSize); }},
    };
}

/// The keys of the ground's colour and the placement.
SetterTable groundSetters()
{
    return {
        {"tint",
         [](const Reader& r) {
             return readRgb(r.entry, r.material.tint, [&](const std::string& what) { return r.fail(what); });
         }},
        {"colour",
         [](const Reader& r) {
             return readRgb(r.entry, r.material.colour, [&](const std::string& what) { return r.fail(what); });
         }},
        {"colour_cover", [](const Reader& r) { return assign(r.number(0.0, 1.0, "[0, 1]"), r.material.colourCover); }},
        {"blend_height",
         [](const Reader& r) { return assign(r.number(0.0, 1e4, "[0, 10000] metres"), r.material.blendHeight); }},
        {"curvature",
         [](const Reader& r) -> Status {
             auto range = r.range(-90.0, 90.0, "degrees in [-90, 90]");
             if (!range) {
                 return range.error();
             }
             r.material.placement.curvatureMin = (*range)[0];
             r.material.placement.curvatureMax = (*range)[1];
             return {};
         }},
        {"curvature_blend",
         [](const Reader& r) {
             return assign(r.number(1e-3, 90.0, "[0.001, 90] degrees"), r.material.placement.curvatureBlend);
         }},
        {"variation",
         [](const Reader& r) -> Status {
             auto list = parseList(r.entry.value);
             if (!list || list->size() != 2 || !((*list)[0] >= 0.0 && (*list)[0] <= 4.0) ||
                 !((*list)[1] >= 1.0 && (*list)[1] <= 1e6)) {
                 return r.fail(
                     "expected 'amount, wavelength': amount in [0, 4] blend widths, wavelength in [1, "
                     "1000000] metres");
             }
             r.material.placement.variationAmount = (*list)[0];
             r.material.placement.variationWavelength = (*list)[1];
             return {};
         }},
        {"slope",
         [](const Reader& r) -> Status {
             auto range = r.range(0.0, 90.0, "degrees in [0, 90]");
             if (!range) {
                 return range.error();
             }
             r.material.placement.slopeMin = (*range)[0];
             r.material.placement.slopeMax = (*range)[1];
             return {};
         }},
        {"slope_blend",
         [](const Reader& r) {
             return assign(r.number(1e-3, 90.0, "[0.001, 90] degrees"), r.material.placement.slopeBlend);
         }},
        {"height",
         [](const Reader& r) -> Status {
             auto range = r.range(-1e5, 1e5, "metres in [-100000, 100000]");
             if (!range) {
                 return range.error();
             }
             r.material.placement.heightMin = (*range)[0];
             r.material.placement.heightMax = (*range)[1];
             return {};
         }},
        {"height_blend",
         [](const Reader& r) {
             return assign(r.number(1e-3, 1e5, "[0.001, 100000] metres"), r.material.placement.heightBlend);
         }},
    };
}

const SetterTable& setters()
{
    static const SetterTable table = [] {
        SetterTable all = displacementSetters();
        all.merge(groundSetters());
        return all;
    }();
    return table;
}

}  // namespace

double placementCurvature(double west, double east, double south, double north, double centre, double spacing)
{
    const double bend = ((west + east) + (south + north) - 4.0 * centre) / (2.0 * spacing);
    return std::atan(bend) * (180.0 / std::numbers::pi);
}

double MaterialPlacement::variation(double x, double y) const
{
    if (variationAmount <= 0.0) {
        return 0.0;
    }
    // Three octaves, each turned and offset so their lattices do not line up; their sum's deviation is about
    // 0.30 * sqrt(1 + 1/4 + 1/16) (PerlinNoise's 0.30 an octave).
    const double u = x / variationWavelength, v = y / variationWavelength;
    const double n = variationNoise(u, v) + 0.5 * variationNoise(1.6 * u - 1.2 * v + 17.3, 1.2 * u + 1.6 * v - 41.9) +
                     0.25 * variationNoise(-1.92 * u - 3.44 * v - 73.1, 3.44 * u - 1.92 * v + 29.7);
    return std::clamp(n / (0.30 * std::sqrt(1.3125)), -3.0, 3.0);
}

double MaterialPlacement::coverage(const PlacementSample& s) const
{
    const double shift = variationAmount > 0.0 ? variationAmount * variation(s.x, s.y) : 0.0;
    return ramp(s.slopeDegrees, slopeMin, slopeMax, slopeBlend, shift, 0.0, 90.0) *
           ramp(s.height, heightMin, heightMax, heightBlend, shift) *
           ramp(s.curvature, curvatureMin, curvatureMax, curvatureBlend, shift, -90.0, 90.0);
}

Expected<Material> parseMaterial(const ConfigFile& config, std::vector<std::string>& warnings)
{
    Material material;
    material.file = config.name();
    material.name = std::filesystem::path(config.name()).stem().string();
    const ConfigEntry* kindEntry = nullptr;
    for (const ConfigEntry& entry : config.entries()) {
        auto it = setters().find(entry.key);
        if (it == setters().end()) {
            warnings.push_back(entry.location() + ": unknown material option '" + entry.key + "' ignored");
            continue;
        }
        if (entry.key == "displacement") {
            kindEntry = &entry;
        }
        TERRAIN_TRY(it->second(Reader{entry, material, config.directory()}));
    }
    // The variation's own noise, apart from the displacement's (the same seed would line their lattices up).
    material.placement.variationNoise = PerlinNoise(material.fractal.seed ^ 0x5bd1e9955bd1e995ull);
    DisplacementKind kind = material.kind;
    bool bitmap = kind == DisplacementKind::BitmapFbm || kind == DisplacementKind::BitmapRidged;
    material.fractal.type = kind == DisplacementKind::Ridged || kind == DisplacementKind::BitmapRidged
                                ? FractalType::Ridged
                                : FractalType::Fbm;
    if (bitmap && material.bitmap.empty()) {
        return makeError(kindEntry->location(), ": displacement = ", kindEntry->value,
                         " needs a 'bitmap = file.png' (a square, tileable gray PNG)");
    }
    std::string problem = validateFractalParams(material.fractal);
    if (!problem.empty()) {  // every key is range-checked above; this guards combinations added later
        return makeError(config.name(), ": ", problem);
    }
    if (kind == DisplacementKind::None) {
        return material;
    }
    std::shared_ptr<const BasisTable> table;
    if (bitmap) {
        auto image = readPngImage(material.bitmap, 1);
        if (!image) {
            return makeError(config.name(), ": bitmap: ", image.error().message);
        }
        if (image->width != image->height || image->width < 4) {
            return makeError(config.name(), ": bitmap ", material.bitmap.string(), " is ", image->width, " x ",
                             image->height, "; a bitmap basis must be square, at least 4 x 4");
        }
        table = std::make_shared<BasisTable>(BasisTable::fromImage(*image));
    }
    material.displacement =
        bitmap ? std::make_shared<Fractal>(material.fractal, table) : std::make_shared<Fractal>(material.fractal);
    material.bitmapTable = table;
    if (material.relativeAmplitude > 0.0) {
        if (material.fractal.amplitude <= 0.0) {
            return makeError(config.name(),
                             ": relative_amplitude needs an amplitude > 0 (its shape, and what it "
                             "falls back to over a map without roughness laws)");
        }
        material.fractalDeviation = fractalMidpointDeviation(*material.displacement);
    }
    return material;
}

double fractalMidpointDeviation(const Fractal& fractal)
{
    const double r = fractal.params().wavelength;
    SplitMix64 random(0x9e3779b97f4a7c15ull ^ fractal.params().seed);
    auto unit = [&] { return static_cast<double>(random.next() >> 11) * 0x1.0p-53; };
    constexpr int kPlaces = 4096;
    double sum = 0.0;
    for (int k = 0; k < kPlaces; ++k) {
        const double x = (unit() - 0.5) * 1e5, y = (unit() - 0.5) * 1e5;
        const double h = fractal(x, y);
        const double dx = h - 0.5 * (fractal(x - r, y) + fractal(x + r, y));
        const double dy = h - 0.5 * (fractal(x, y - r) + fractal(x, y + r));
        sum += dx * dx + dy * dy;
    }
    return std::sqrt(sum / (2.0 * kPlaces));
}

Material relativeTo(const Material& material, double dataSpacing)
{
    TERRAIN_EXPECTS(dataSpacing > 0.0, "a spacing must be > 0");
    if (material.relativeAmplitude <= 0.0 || !material.displacement) {
        return material;
    }
    Material out = material;
    int drop = 0;
    double wavelength = material.fractal.wavelength;
    while (drop < material.fractal.octaves && wavelength >= dataSpacing) {
        wavelength /= material.fractal.lacunarity;
        ++drop;
    }
    if (drop == 0) {
        return out;
    }
    if (drop == material.fractal.octaves) {
        out.kind = DisplacementKind::None;
        out.displacement = nullptr;
        out.fractalDeviation = 0.0;
        return out;
    }
    out.fractal.octaves -= drop;
    out.fractal.wavelength = wavelength;
    out.fractal.amplitude *= std::pow(material.fractal.gain, drop);
    out.displacement = material.bitmapTable ? std::make_shared<Fractal>(out.fractal, material.bitmapTable)
                                            : std::make_shared<Fractal>(out.fractal);
    out.fractalDeviation = fractalMidpointDeviation(*out.displacement);
    return out;
}

Expected<Material> loadMaterial(const std::filesystem::path& path, std::vector<std::string>& warnings)
{
    auto config = ConfigFile::load(path);
    if (!config) {
        return config.error();
    }
    return parseMaterial(*config, warnings);
}

MaterialSet::MaterialSet(std::vector<Material> materials) : mMaterials(std::move(materials))
{
    TERRAIN_EXPECTS(!mMaterials.empty(), "a material set needs at least one material");
}

Expected<MaterialSet> MaterialSet::load(const std::vector<std::filesystem::path>& files,
                                        std::vector<std::string>& warnings)
{
    if (files.empty()) {
        return makeError("no material files given");
    }
    std::vector<Material> materials;
    for (const auto& file : files) {
        auto material = loadMaterial(file, warnings);
        if (!material) {
            return material.error();
        }
        materials.push_back(std::move(material).value());
    }
    return MaterialSet(std::move(materials));
}

MaterialSet MaterialSet::relativeTo(double dataSpacing) const
{
    std::vector<Material> adapted;
    for (const Material& m : mMaterials) {
        adapted.push_back(terrain::relativeTo(m, dataSpacing));
    }
    return MaterialSet(std::move(adapted));
}

bool MaterialSet::hasRelative() const
{
    return std::any_of(mMaterials.begin(), mMaterials.end(),
                       [](const Material& m) { return m.relativeAmplitude > 0.0 && m.displacement; });
}

bool MaterialSet::blendsByHeight() const
{
    return std::any_of(mMaterials.begin() + 1, mMaterials.end(), [](const Material& m) { return m.blendHeight > 0.0; });
}

bool MaterialSet::usesCurvature() const
{
    return std::any_of(mMaterials.begin() + 1, mMaterials.end(), [](const Material& m) {
        return m.placement.curvatureMin > -90.0 || m.placement.curvatureMax < 90.0;
    });
}

namespace {

/// Coverages c[0 .. n) at `sample` (c[0] = 1: the ground).
void coverages(const std::vector<Material>& materials, const PlacementSample& sample, std::span<double> c)
{
    c[0] = 1.0;
    for (std::size_t m = 1; m < materials.size(); ++m) {
        c[m] = materials[m].placement.coverage(sample);
    }
}

/// Weights from coverages `c` (overwritten by the height-blended ones), with each material's displacement `d`
/// where height blending applies (d empty: none).
void weightsFromCoverages(const std::vector<Material>& materials, std::span<double> c, std::span<const double> d,
                          std::span<double> out)
{
    const std::size_t n = materials.size();
    if (!d.empty()) {
        // Bottom up: `below` is the displacement of the layers under material m as they are blended.
        double below = d[0];
        for (std::size_t m = 1; m < n; ++m) {
            const double b = materials[m].blendHeight;
            if (b > 0.0 && c[m] > 0.0 && c[m] < 1.0) {
                c[m] = std::clamp(c[m] + 4.0 * c[m] * (1.0 - c[m]) * (d[m] - below) / b, 0.0, 1.0);
            }
            below += c[m] * (d[m] - below);
        }
    }
    // Painter's order from the top: the last material keeps its coverage, each one below keeps what the
    // ones above leave uncovered; material 0 takes the rest, so the sum is 1 by construction.
    double uncovered = 1.0;
    for (std::size_t m = n; m-- > 1;) {
        out[m] = c[m] * uncovered;
        uncovered *= 1.0 - c[m];
    }
    out[0] = uncovered;
}

}  // namespace

void MaterialSet::weights(const PlacementSample& sample, std::span<const double> displacements,
                          std::span<double> out) const
{
    const std::size_t n = mMaterials.size();
    TERRAIN_EXPECTS(out.size() >= n, "out must hold one weight per material");
    TERRAIN_EXPECTS(displacements.empty() || displacements.size() >= n, "one displacement per material (or none)");
    std::vector<double> c(n);
    coverages(mMaterials, sample, c);
    weightsFromCoverages(mMaterials, c, blendsByHeight() ? displacements : std::span<const double>(), out);
}

float MaterialSet::displacement(const PlacementSample& sample) const
{
    const std::size_t n = mMaterials.size();
    std::vector<double> c(n), w(n);
    coverages(mMaterials, sample, c);
    weightsFromCoverages(mMaterials, c, {}, w);
    double sum = 0.0;
    for (std::size_t m = 0; m < n; ++m) {
        if (w[m] != 0.0) {
            sum += w[m] * static_cast<double>(static_cast<float>(mMaterials[m].displacementAt(sample.x, sample.y)));
        }
    }
    return static_cast<float>(sum);
}

MaterialSet::CoverTerms MaterialSet::coverTerms(std::size_t m) const
{
    TERRAIN_EXPECTS(m < mMaterials.size(), "no such material");
    const Material& material = mMaterials[m];
    // A third of the tint, divided by the tint's brightness so that it shifts the hue, not the brightness.
    constexpr double kTintStrength = 0.35;
    const auto& t = material.tint;
    const double luminance = 0.2126 * t[0] + 0.7152 * t[1] + 0.0722 * t[2];
    CoverTerms terms{};
    for (std::size_t i = 0; i < 3; ++i) {
        const double tint = luminance > 0.0 ? t[i] / luminance : 1.0;
        terms.scale[i] = (1.0 + kTintStrength * (tint - 1.0)) * (1.0 - material.colourCover);
        terms.offset[i] = material.colourCover * material.colour[i];
    }
    return terms;
}

std::array<float, 3> MaterialSet::cover(const std::array<float, 3>& rgb, std::span<const double> weights) const
{
    TERRAIN_EXPECTS(weights.size() >= mMaterials.size(), "one weight per material");
    std::array<double, 3> sum = {0.0, 0.0, 0.0};
    for (std::size_t m = 0; m < mMaterials.size(); ++m) {
        if (weights[m] == 0.0) {
            continue;
        }
        const CoverTerms terms = coverTerms(m);
        for (std::size_t i = 0; i < 3; ++i) {
            sum[i] += weights[m] * (rgb[i] * terms.scale[i] + terms.offset[i]);
        }
    }
    return {static_cast<float>(std::clamp(sum[0], 0.0, 1.0)), static_cast<float>(std::clamp(sum[1], 0.0, 1.0)),
            static_cast<float>(std::clamp(sum[2], 0.0, 1.0))};
}

void MaterialSet::displacementGrid(const SampleGrid& grid, std::span<const float> slopeDegrees,
                                   std::span<const float> heights, std::span<float> out,
                                   std::span<const std::uint8_t> mask, std::span<const std::vector<float>> scales,
                                   std::span<const float> curvature, std::span<std::uint8_t> weightsOut) const
{
    TERRAIN_EXPECTS(scales.empty() || scales.size() == mMaterials.size(), "one scale grid (or none) per material");
    TERRAIN_EXPECTS(grid.width >= 0 && grid.height >= 0 && grid.spacing > 0.0, "grid size >= 0 and spacing > 0");
    const std::size_t count = grid.count();
    TERRAIN_EXPECTS(slopeDegrees.size() >= count && heights.size() >= count && out.size() >= count,
                    "slope, height and out must hold width * height samples");
    TERRAIN_EXPECTS(curvature.empty() || curvature.size() >= count, "curvature must be empty or hold every sample");
    TERRAIN_EXPECTS(mask.empty() || mask.size() >= count, "the mask must hold width * height entries");
    const std::size_t n = mMaterials.size();
    TERRAIN_EXPECTS(weightsOut.empty() || weightsOut.size() >= count * n, "weightsOut must hold n per sample");
    // Coverages first. A material is evaluated where it has weight; where weights are asked for and materials
    // blend by height, wherever it covers anything (the ground everywhere), since the blend reads it there.
    const bool byHeight = !weightsOut.empty() && blendsByHeight();
    std::vector<double> c(count * n);
    std::vector<double> w(count * n);
    std::vector<std::uint8_t> used(n * count, 0);  // per material: the samples it must be evaluated at
    std::vector<char> any(n, 0);
    std::vector<double> unblended(n);
    for (int j = 0; j < grid.height; ++j) {
        for (int i = 0; i < grid.width; ++i) {
            const std::size_t k =
                static_cast<std::size_t>(j) * static_cast<std::size_t>(grid.width) + static_cast<std::size_t>(i);
            if (!mask.empty() && mask[k] == 0) {
                continue;
            }
            const PlacementSample sample{slopeDegrees[k], heights[k], curvature.empty() ? 0.0 : curvature[k], grid.x(i),
                                         grid.y(j)};
            const std::span<double> ck(c.data() + k * n, n);
            coverages(mMaterials, sample, ck);
            std::copy(ck.begin(), ck.end(), unblended.begin());
            weightsFromCoverages(mMaterials, unblended, {}, std::span<double>(w.data() + k * n, n));
            for (std::size_t m = 0; m < n; ++m) {
                if (byHeight ? ck[m] != 0.0 : w[k * n + m] != 0.0) {
                    used[m * count + k] = 1;
                    any[m] = 1;
                }
            }
        }
    }
    std::vector<double> d(count * n, 0.0);
    std::vector<float> values(count);
    for (std::size_t m = 0; m < n; ++m) {
        if (!any[m] || !mMaterials[m].displacement) {
            continue;
        }
        mMaterials[m].displacement->evaluateGrid(grid, values,
                                                 std::span<const std::uint8_t>(used.data() + m * count, count));
        const bool scaled = !scales.empty() && !scales[m].empty();
        TERRAIN_EXPECTS(!scaled || scales[m].size() >= count, "a scale grid holds width * height values");
        for (std::size_t k = 0; k < count; ++k) {
            if (used[m * count + k] != 0) {
                const double value = static_cast<double>(values[k]);
                d[k * n + m] = scaled ? value * static_cast<double>(scales[m][k]) : value;
            }
        }
    }
    std::vector<double> shown(n);
    for (std::size_t k = 0; k < count; ++k) {
        if (!mask.empty() && mask[k] == 0) {
            continue;
        }
        const std::span<const double> dk(d.data() + k * n, n);
        double sum = 0.0;
        for (std::size_t m = 0; m < n; ++m) {
            if (w[k * n + m] != 0.0) {
                sum += w[k * n + m] * dk[m];
            }
        }
        out[k] = static_cast<float>(sum);
        if (weightsOut.empty()) {
            continue;
        }
        const double* wk = w.data() + k * n;
        if (byHeight) {
            weightsFromCoverages(mMaterials, std::span<double>(c.data() + k * n, n), dk, shown);
            wk = shown.data();
        }
        for (std::size_t m = 0; m < n; ++m) {
            weightsOut[k * n + m] = static_cast<std::uint8_t>(std::lround(std::clamp(wk[m], 0.0, 1.0) * 255.0));
        }
    }
}

}  // namespace terrain
