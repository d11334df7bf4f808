// Materials (paper 3.4.5) and their placement by slope and height with smooth, seam-free blending.
#include "synthesis/Material.h"

#include "core/Check.h"
#include "core/Parse.h"
#include "core/SplitMix64.h"
#include "heightfield/Image.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>

namespace terrain {

namespace {

double smoothstep(double t)
{
    t = std::clamp(t, 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

/// 1 inside [lo, hi], smoothstep down to 0 over `blend` outside.
double ramp(double value, double lo, double hi, double blend)
{
    double outside = value < lo ? lo - value : (value > hi ? value - hi : 0.0);
    return smoothstep(1.0 - outside / blend);
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

const std::map<std::string, Setter, std::less<>>& setters()
{
    static const std::map<std::string, Setter, std::less<>> table = {
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
        {"tint",
         [](const Reader& r) -> Status {
             auto list = parseList(r.entry.value);
             if (!list || list->size() != 3 ||
                 std::any_of(list->begin(), list->end(), [](double c) { return c < 0.0 || c > 1.0; })) {
                 return r.fail("expected 'r, g, b', each in [0, 1]");
             }
             for (int i = 0; i < 3; ++i) {
                 r.material.tint[i] = static_cast<float>((*list)[i]);
             }
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
    return table;
}

}  // namespace

double MaterialPlacement::coverage(double slopeDegrees, double height) const
{
    return ramp(slopeDegrees, slopeMin, slopeMax, slopeBlend) * ramp(height, heightMin, heightMax, heightBlend);
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

void MaterialSet::weights(double slopeDegrees, double height, std::span<double> out) const
{
    TERRAIN_EXPECTS(out.size() >= mMaterials.size(), "out must hold one weight per material");
    // Painter's order from the top: the last material keeps its coverage, each one below keeps what the
    // ones above leave uncovered; material 0 takes the rest, so the sum is 1 by construction.
    double uncovered = 1.0;
    for (std::size_t m = mMaterials.size(); m-- > 1;) {
        double c = mMaterials[m].placement.coverage(slopeDegrees, height);
        out[m] = c * uncovered;
        uncovered *= 1.0 - c;
    }
    out[0] = uncovered;
}

float MaterialSet::displacement(double x, double y, double slopeDegrees, double height) const
{
    constexpr std::size_t kInline = 16;
    double stack[kInline];
    std::vector<double> heap;
    std::span<double> w(stack, kInline);
    if (mMaterials.size() > kInline) {
        heap.resize(mMaterials.size());
        w = heap;
    }
    weights(slopeDegrees, height, w);
    double sum = 0.0;
    for (std::size_t m = 0; m < mMaterials.size(); ++m) {
        if (w[m] != 0.0) {
            sum += w[m] * static_cast<double>(static_cast<float>(mMaterials[m].displacementAt(x, y)));
        }
    }
    return static_cast<float>(sum);
}

void MaterialSet::displacementGrid(const SampleGrid& grid, std::span<const float> slopeDegrees,
                                   std::span<const float> heights, std::span<float> out,
                                   std::span<const std::uint8_t> mask, std::span<const std::vector<float>> scales) const
{
    TERRAIN_EXPECTS(scales.empty() || scales.size() == mMaterials.size(), "one scale grid (or none) per material");
    TERRAIN_EXPECTS(grid.width >= 0 && grid.height >= 0 && grid.spacing > 0.0, "grid size >= 0 and spacing > 0");
    const std::size_t count = grid.count();
    TERRAIN_EXPECTS(slopeDegrees.size() >= count && heights.size() >= count && out.size() >= count,
                    "slope, height and out must hold width * height samples");
    TERRAIN_EXPECTS(mask.empty() || mask.size() >= count, "the mask must hold width * height entries");
    const std::size_t n = mMaterials.size();
    std::vector<double> w(count * n);
    std::vector<std::uint8_t> used(n * count, 0);  // per material: the samples it must be evaluated at
    std::vector<char> any(n, 0);
    for (std::size_t k = 0; k < count; ++k) {
        if (!mask.empty() && mask[k] == 0) {
            continue;
        }
        weights(slopeDegrees[k], heights[k], std::span<double>(w.data() + k * n, n));
        for (std::size_t m = 0; m < n; ++m) {
            if (w[k * n + m] != 0.0) {
                used[m * count + k] = 1;
                any[m] = 1;
            }
        }
    }
    std::vector<double> sum(count, 0.0);
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
                sum[k] += w[k * n + m] * (scaled ? value * static_cast<double>(scales[m][k]) : value);
            }
        }
    }
    for (std::size_t k = 0; k < count; ++k) {
        if (mask.empty() || mask[k] != 0) {
            out[k] = static_cast<float>(sum[k]);
        }
    }
}

}  // namespace terrain
