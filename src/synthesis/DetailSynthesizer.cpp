// Dynamic node synthesis (paper 3.4.3 "Adding Nodes to the Quadtree", 4.2.4 "Detail Generation System").
#include "synthesis/DetailSynthesizer.h"

#include "core/Check.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace terrain {

Expected<std::unique_ptr<const DetailSynthesizer>> DetailSynthesizer::create(int chunkSize, DetailSettings settings)
{
    TERRAIN_EXPECTS(isValidChunkSize(chunkSize), "chunk size must be 2^k + 1 in [3, 1025]");
    if (!(std::isfinite(settings.omega) && settings.omega >= 0.0 && settings.omega <= 2.0)) {
        return makeError("detail_subdivision_factor ", settings.omega, " must be in [0, 2]");
    }
    if (settings.materials && settings.materials->materials().size() > kMaxDetailMaterials) {
        return makeError("a material set holds at most ", kMaxDetailMaterials, " materials, not ",
                         settings.materials->materials().size());
    }
    if (settings.roughness && settings.roughness->leafCells() != chunkSize - 1) {
        return makeError("the roughness noise is for leaves of ", settings.roughness->leafCells() + 1,
                         " samples a side, the synthesizer for ", chunkSize);
    }
    if (settings.laws && settings.laws->leafCells() != chunkSize - 1) {
        return makeError("the roughness laws are for leaves of ", settings.laws->leafCells() + 1,
                         " samples a side, the synthesizer for ", chunkSize);
    }
    auto subdivider = makeSubdivider(settings.scheme, chunkSize, settings.omega);
    TERRAIN_TRY(subdivider);
    return std::unique_ptr<const DetailSynthesizer>(
        new DetailSynthesizer(std::move(subdivider.value()), std::move(settings)));
}

DetailSettings settingsForMap(DetailSettings settings, const MapHeader& header, bool roughness)
{
    settings.roughness = nullptr;
    settings.laws = nullptr;
    if (!header.roughness) {
        return settings;
    }
    if (settings.materials) {
        settings.materials = std::make_shared<const MaterialSet>(settings.materials->relativeTo(header.sampleSpacing));
    }
    settings.laws = makeRoughnessNoise(header, settings.materials.get());
    settings.roughness = roughness ? settings.laws : nullptr;
    return settings;
}

WindowPlacement windowPlacement(const MapHeader& h, const NodeId& id)
{
    const std::int64_t cells = h.chunkSize - 1;
    return {h.originX,
            h.originY,
            h.heightOffset,
            h.spacingAt(id.level),
            static_cast<std::int64_t>(id.x) * cells - kBorder,
            static_cast<std::int64_t>(id.y) * cells - kBorder};
}

WindowPlacement childPlacement(const WindowPlacement& parent, int quadrant, int chunkSize)
{
    TERRAIN_EXPECTS(quadrant >= 0 && quadrant < 4, "quadrant must be 0..3");
    // Window sample 0 of a node at position X is global sample X (N - 1) - border, at the node's level.
    const std::int64_t cells = chunkSize - 1;
    WindowPlacement child = parent;
    child.spacing = parent.spacing * 0.5;
    child.gx0 = 2 * (parent.gx0 + kBorder) + (quadrant & 1) * cells - kBorder;
    child.gy0 = 2 * (parent.gy0 + kBorder) + (quadrant >> 1) * cells - kBorder;
    return child;
}

DetailSynthesizer::DetailSynthesizer(std::unique_ptr<Subdivider> subdivider, DetailSettings settings)
    : mSubdivider(std::move(subdivider)), mSettings(std::move(settings))
{
    const int w = windowSize();
    mNewSamples.assign(static_cast<std::size_t>(w) * w, 0);
    for (int j = 0; j < w; ++j) {
        for (int i = 0; i < w; ++i) {
            // Window index c is child coordinate c - 2: even c lies on a parent sample.
            mNewSamples[static_cast<std::size_t>(j) * w + i] = (i % 2 != 0 || j % 2 != 0) ? 1 : 0;
        }
    }
    if (mSettings.materials && mSettings.laws) {
        for (const Material& m : mSettings.materials->materials()) {
            const bool relative = m.relativeAmplitude > 0.0 && m.displacement && m.fractalDeviation > 0.0;
            mRelativeFactor.push_back(relative ? m.relativeAmplitude / m.fractalDeviation : 0.0);
        }
    }
}

std::vector<std::vector<float>> DetailSynthesizer::materialScales(std::int64_t gx0, std::int64_t gy0, int width,
                                                                  int height, double spacing) const
{
    std::vector<std::vector<float>> scales;
    if (mRelativeFactor.empty()) {
        return scales;
    }
    const auto& materials = mSettings.materials->materials();
    scales.resize(materials.size());
    for (std::size_t m = 0; m < materials.size(); ++m) {
        if (!isRelative(m)) {
            continue;
        }
        std::vector<float>& out = scales[m];
        out.resize(static_cast<std::size_t>(width) * height);
        mSettings.laws->deviationGrid(gx0, gy0, width, height, spacing, materials[m].fractal.wavelength, out);
        const auto factor = static_cast<float>(mRelativeFactor[m]);
        for (float& v : out) {
            v *= factor;
        }
    }
    return scales;
}

std::vector<std::vector<float>> DetailSynthesizer::nodeMaterialScales(const WindowPlacement& where) const
{
    return materialScales(where.gx0 + kBorder, where.gy0 + kBorder, chunkSize(), chunkSize(), where.spacing);
}

double DetailSynthesizer::materialBound() const
{
    double bound = 0.0;
    if (!mSettings.materials) {
        return bound;
    }
    const auto& materials = mSettings.materials->materials();
    for (std::size_t m = 0; m < materials.size(); ++m) {
        if (!materials[m].displacement) {
            continue;
        }
        const double amplitude = materials[m].fractal.amplitude;
        bound = std::max(bound, isRelative(m) ? amplitude * mRelativeFactor[m] *
                                                    mSettings.laws->maxDeviation(materials[m].fractal.wavelength)
                                              : amplitude);
    }
    return bound;
}

namespace {

/// atan(g) for g >= 0, |error| < 1e-5 rad (a minimax polynomial on [0, 1] and atan(g) = pi/2 - atan(1/g)
/// above): a few multiplications instead of a libm call, for the thousands of slopes of every node.
/// Deterministic like any arithmetic here (-ffp-contract=off).
double fastAtan(double g)
{
    const bool inverted = g > 1.0;
    const double x = inverted ? 1.0 / g : g;
    const double x2 = x * x;
    const double a =
        x * (0.99997726 +
             x2 * (-0.33262347 + x2 * (0.19354346 + x2 * (-0.11643287 + x2 * (0.05265332 + x2 * -0.01172120)))));
    return inverted ? std::numbers::pi / 2 - a : a;
}

}  // namespace

double DetailSynthesizer::slopeDegrees(const DualHeightMap& map, int i, int j, double spacing) const
{
    const int w = map.size;
    auto at = [&](int x, int y) { return static_cast<double>(map.base[static_cast<std::size_t>(y) * w + x]); };
    const int x0 = std::max(i - 1, 0), x1 = std::min(i + 1, w - 1);
    const int y0 = std::max(j - 1, 0), y1 = std::min(j + 1, w - 1);
    const double dx = (at(x1, j) - at(x0, j)) / ((x1 - x0) * spacing);
    const double dy = (at(i, y1) - at(i, y0)) / ((y1 - y0) * spacing);
    return fastAtan(std::sqrt(dx * dx + dy * dy)) * (180.0 / std::numbers::pi);
}

void DetailSynthesizer::displace(const WindowPlacement& where, const DualHeightMap* parent, int quadrant,
                                 DualHeightMap& map, ShownWeights shown) const
{
    const int w = windowSize();
    TERRAIN_EXPECTS(map.size == w && map.base.size() == static_cast<std::size_t>(w) * w,
                    "the map's window does not match the synthesizer's chunk size");
    if (!addsDisplacement()) {
        map.displacement.clear();
        map.slope.clear();
        map.curvature.clear();
        map.weights.clear();
        return;
    }
    const std::size_t count = static_cast<std::size_t>(w) * w;
    map.displacement.assign(count, 0.0f);
    const int half = (chunkSize() - 1) / 2;
    const int px0 = 1 + (quadrant & 1) * half, py0 = 1 + (quadrant >> 1) * half;
    if (parent) {
        TERRAIN_EXPECTS(parent->size == w && parent->displacement.size() == count, "the parent has no displacement");
        TERRAIN_EXPECTS(quadrant >= 0 && quadrant < 4, "quadrant must be 0..3");
        // Even samples have the parent's position, slope and height: its displacement, bit for bit (the
        // roughness octave this level adds is zero there).
        for (int j = 0; j < w; j += 2) {
            for (int i = 0; i < w; i += 2) {
                map.displacement[static_cast<std::size_t>(j) * w + i] =
                    parent->displacement[static_cast<std::size_t>(py0 + j / 2) * w + px0 + i / 2];
            }
        }
    }
    const std::span<const std::uint8_t> mask =
        parent ? std::span<const std::uint8_t>(mNewSamples) : std::span<const std::uint8_t>();
    if (addsMaterials()) {
        displaceByMaterials(where, parent, px0, py0, shown == ShownWeights::Keep, mask, map);
    } else {
        map.slope.clear();
        map.curvature.clear();
        map.weights.clear();
    }
    if (mSettings.roughness) {
        mSettings.roughness->add(where.gx0, where.gy0, w, w, mSettings.roughness->levelsBelow(where.spacing),
                                 map.displacement, mask);
    }
}

void DetailSynthesizer::roughnessTails(const WindowPlacement& where, int levelsDown, std::span<float> out) const
{
    TERRAIN_EXPECTS(levelsDown >= 0 && levelsDown <= 16, "levelsDown must be in [0, 16]");
    const int scale = 1 << levelsDown;
    const int cells = (chunkSize() - 1) * scale;
    TERRAIN_EXPECTS(out.size() >= static_cast<std::size_t>(cells) * cells, "out must hold one value a cell");
    if (!mSettings.roughness) {
        std::fill(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(cells) * cells, 0.0f);
        return;
    }
    mSettings.roughness->cellTails(where.spacing / scale, (where.gx0 + kBorder) * scale, (where.gy0 + kBorder) * scale,
                                   cells, out);
}

void DetailSynthesizer::displaceByMaterials(const WindowPlacement& where, const DualHeightMap* parent, int px0, int py0,
                                            bool keepWeights, std::span<const std::uint8_t> mask,
                                            DualHeightMap& map) const
{
    const int w = windowSize();
    const std::size_t count = static_cast<std::size_t>(w) * w;
    const MaterialSet& set = *mSettings.materials;
    // One material covers everything: its weight is 1 whatever the slope and height.
    const bool placed = set.materials().size() > 1;
    const bool curved = placed && set.usesCurvature();
    if (parent) {
        TERRAIN_EXPECTS(!placed || parent->slope.size() == count, "the parent has no placement slopes");
        TERRAIN_EXPECTS(!curved || parent->curvature.size() == count, "the parent has no placement curvatures");
        TERRAIN_EXPECTS(!placed || !keepWeights || parent->weights.size() == count * kMaxDetailMaterials,
                        "the parent has no material weights");
    }
    std::vector<float> height;
    map.curvature.clear();
    map.weights.clear();
    if (placed) {
        // The placement fields (slope, curvature): a node without a parent measures its own base; a child
        // interpolates its parent's linearly (even samples copy them, odd ones average the two or four around
        // them), so below a static node the placement, and hence every sample's displacement and weights, is
        // the same at every depth: the fields of the deepest static level, continued smoothly.
        map.slope.assign(count, 0.0f);
        if (curved) {
            map.curvature.assign(count, 0.0f);
        }
        height.resize(count);
        auto interpolated = [&](const std::vector<float>& field, int i, int j) {
            auto at = [&](int pi, int pj) { return field[static_cast<std::size_t>(pj) * w + pi]; };
            // Window index c is parent window index p0 + c / 2 (even c) or between that and the next.
            const int pi = px0 + i / 2, pj = py0 + j / 2;
            if (i % 2 == 0 && j % 2 == 0) {
                return at(pi, pj);
            }
            if (j % 2 == 0) {
                return 0.5f * (at(pi, pj) + at(pi + 1, pj));
            }
            if (i % 2 == 0) {
                return 0.5f * (at(pi, pj) + at(pi, pj + 1));
            }
            return 0.25f * ((at(pi, pj) + at(pi + 1, pj)) + (at(pi, pj + 1) + at(pi + 1, pj + 1)));
        };
        for (int j = 0; j < w; ++j) {
            for (int i = 0; i < w; ++i) {
                const std::size_t k = static_cast<std::size_t>(j) * w + i;
                height[k] = static_cast<float>(where.heightOffset + map.base[k]);
                if (parent) {
                    map.slope[k] = interpolated(parent->slope, i, j);
                    if (curved) {
                        map.curvature[k] = interpolated(parent->curvature, i, j);
                    }
                    continue;
                }
                map.slope[k] = static_cast<float>(slopeDegrees(map, i, j, where.spacing));
                if (curved) {
                    // The window's edge takes its neighbour's (the field is only read inside it).
                    const int ci = std::clamp(i, 1, w - 2), cj = std::clamp(j, 1, w - 2);
                    auto base = [&](int x, int y) {
                        return static_cast<double>(map.base[static_cast<std::size_t>(y) * w + x]);
                    };
                    map.curvature[k] =
                        static_cast<float>(placementCurvature(base(ci - 1, cj), base(ci + 1, cj), base(ci, cj - 1),
                                                              base(ci, cj + 1), base(ci, cj), where.spacing));
                }
            }
        }
    } else {
        map.slope.clear();
        height.assign(count, 0.0f);
    }
    std::vector<float> noSlope;
    if (!placed) {
        noSlope.assign(count, 0.0f);
    }
    const std::size_t n = set.materials().size();
    std::vector<std::uint8_t> weights;
    if (placed && keepWeights) {
        weights.assign(count * n, 0);
    }
    const std::vector<std::vector<float>> scales = materialScales(where.gx0, where.gy0, w, w, where.spacing);
    set.displacementGrid(where.grid(w), placed ? std::span<const float>(map.slope) : noSlope, height, map.displacement,
                         mask, scales, map.curvature, weights);
    if (weights.empty()) {
        return;
    }
    // Four bytes a sample; even samples of a child copy the parent's, as their displacement does.
    map.weights.assign(count * kMaxDetailMaterials, 0);
    for (int j = 0; j < w; ++j) {
        for (int i = 0; i < w; ++i) {
            const std::size_t k = static_cast<std::size_t>(j) * w + i;
            std::uint8_t* to = map.weights.data() + k * kMaxDetailMaterials;
            if (parent && i % 2 == 0 && j % 2 == 0) {
                const std::size_t p = static_cast<std::size_t>(py0 + j / 2) * w + static_cast<std::size_t>(px0 + i / 2);
                std::copy_n(parent->weights.data() + p * kMaxDetailMaterials, kMaxDetailMaterials, to);
            } else {
                std::copy_n(weights.data() + k * n, n, to);
            }
        }
    }
}

DualHeightMap DetailSynthesizer::synthesizeChild(const DualHeightMap& parent, int quadrant,
                                                 const WindowPlacement& where, ShownWeights shown) const
{
    const int w = windowSize();
    TERRAIN_EXPECTS(parent.size == w && parent.base.size() == static_cast<std::size_t>(w) * w,
                    "the parent's window does not match the synthesizer's chunk size");
    DualHeightMap child;
    child.size = w;
    child.base.resize(static_cast<std::size_t>(w) * w);
    mSubdivider->subdivide(parent.base, quadrant, child.base);
    displace(where, parent.hasDisplacement() ? &parent : nullptr, quadrant, child, shown);
    return child;
}

std::array<DualHeightMap, 4> DetailSynthesizer::synthesizeChildren(const DualHeightMap& parent,
                                                                   const WindowPlacement& where,
                                                                   ShownWeights shown) const
{
    std::array<DualHeightMap, 4> children;
    for (int q = 0; q < 4; ++q) {
        children[static_cast<std::size_t>(q)] =
            synthesizeChild(parent, q, childPlacement(where, q, chunkSize()), shown);
    }
    return children;
}

std::vector<std::uint8_t> DetailSynthesizer::materialWeights(const DualHeightMap& map) const
{
    if (!addsMaterials()) {
        return {};
    }
    const int n = chunkSize();
    const int w = windowSize();
    std::vector<std::uint8_t> out(static_cast<std::size_t>(n) * n * 4, 0);
    if (mSettings.materials->materials().size() == 1) {
        for (std::size_t k = 0; k < out.size(); k += 4) {
            out[k] = 255;
        }
        return out;
    }
    TERRAIN_EXPECTS(map.weights.size() == static_cast<std::size_t>(w) * w * 4,
                    "the map was not displaced with its materials (DetailSynthesizer::displace)");
    for (int j = 0; j < n; ++j) {
        const std::size_t from = (static_cast<std::size_t>(j + kBorder) * w + kBorder) * 4;
        std::copy_n(map.weights.data() + from, static_cast<std::size_t>(n) * 4,
                    out.data() + static_cast<std::size_t>(j) * n * 4);
    }
    return out;
}

std::vector<std::uint8_t> DetailSynthesizer::displacementWeights(const DualHeightMap& map,
                                                                 const WindowPlacement& where) const
{
    if (!addsMaterials()) {
        return {};
    }
    const int n = chunkSize();
    const int w = windowSize();
    const auto& set = *mSettings.materials;
    std::vector<std::uint8_t> out(static_cast<std::size_t>(n) * n * 4, 0);
    if (set.materials().size() == 1) {
        for (std::size_t k = 0; k < out.size(); k += 4) {
            out[k] = 255;
        }
        return out;
    }
    const SampleGrid grid = where.grid(w);
    double weights[kMaxDetailMaterials] = {};
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            const int wi = i + kBorder, wj = j + kBorder;
            const std::size_t k = static_cast<std::size_t>(wj) * w + wi;
            const PlacementSample sample{map.slope.empty() ? slopeDegrees(map, wi, wj, where.spacing) : map.slope[k],
                                         where.heightOffset + map.base[k],
                                         map.curvature.empty() ? 0.0 : map.curvature[k], grid.x(wi), grid.y(wj)};
            set.weights(sample, {}, weights);
            std::uint8_t* px = out.data() + (static_cast<std::size_t>(j) * n + i) * 4;
            for (std::size_t m = 0; m < set.materials().size(); ++m) {
                px[m] = static_cast<std::uint8_t>(std::lround(std::clamp(weights[m], 0.0, 1.0) * 255.0));
            }
        }
    }
    return out;
}

std::vector<std::uint8_t> upsampleTexture(std::span<const std::uint8_t> parent, int textureSize, int quadrant)
{
    const int t = textureSize;
    TERRAIN_EXPECTS(isPowerOfTwoPlusOne(t), "texture size must be 2^k + 1");
    TERRAIN_EXPECTS(parent.size() >= static_cast<std::size_t>(t) * t * 3, "the parent texture holds T * T RGB texels");
    const int half = (t - 1) / 2;
    const int px0 = (quadrant & 1) * half, py0 = (quadrant >> 1) * half;
    std::vector<std::uint8_t> out(static_cast<std::size_t>(t) * t * 3);
    auto texel = [&](int x, int y) { return parent.data() + (static_cast<std::size_t>(y) * t + x) * 3; };
    for (int j = 0; j < t; ++j) {
        const int y0 = py0 + j / 2, y1 = py0 + (j + 1) / 2;
        for (int i = 0; i < t; ++i) {
            const int x0 = px0 + i / 2, x1 = px0 + (i + 1) / 2;
            std::uint8_t* o = out.data() + (static_cast<std::size_t>(j) * t + i) * 3;
            for (int c = 0; c < 3; ++c) {
                const int sum = texel(x0, y0)[c] + texel(x1, y0)[c] + texel(x0, y1)[c] + texel(x1, y1)[c];
                o[c] = static_cast<std::uint8_t>((sum + 2) / 4);
            }
        }
    }
    return out;
}

std::vector<std::uint8_t> coverTexture(const MaterialSet& materials, std::span<const std::uint8_t> rgb, int textureSize,
                                       std::span<const std::uint8_t> weights, int chunkSize)
{
    const int t = textureSize, n = chunkSize;
    TERRAIN_EXPECTS(t >= 2 && n >= 2, "texture and chunk sizes must be >= 2");
    TERRAIN_EXPECTS(rgb.size() >= static_cast<std::size_t>(t) * t * 3, "the texture holds T * T RGB texels");
    TERRAIN_EXPECTS(weights.size() >= static_cast<std::size_t>(n) * n * 4, "the weights hold N * N * 4 bytes");
    const std::size_t count = materials.materials().size();
    TERRAIN_EXPECTS(count <= kMaxDetailMaterials, "at most kMaxDetailMaterials materials");
    std::vector<std::uint8_t> out(static_cast<std::size_t>(t) * t * 3);
    std::array<MaterialSet::CoverTerms, kMaxDetailMaterials> terms{};
    for (std::size_t m = 0; m < count; ++m) {
        terms[m] = materials.coverTerms(m);
    }
    const double scale = static_cast<double>(n - 1) / static_cast<double>(t - 1);
    auto weightAt = [&](int i, int j, std::size_t m) {
        return static_cast<double>(weights[(static_cast<std::size_t>(j) * n + i) * 4 + m]);
    };
    for (int j = 0; j < t; ++j) {
        const double y = j * scale;
        const int y0 = std::min(static_cast<int>(y), n - 2);
        const double fy = y - y0;
        for (int i = 0; i < t; ++i) {
            const double x = i * scale;
            const int x0 = std::min(static_cast<int>(x), n - 2);
            const double fx = x - x0;
            std::array<double, kMaxDetailMaterials> w = {};
            double total = 0.0;
            for (std::size_t m = 0; m < count; ++m) {
                w[m] = (1.0 - fy) * ((1.0 - fx) * weightAt(x0, y0, m) + fx * weightAt(x0 + 1, y0, m)) +
                       fy * ((1.0 - fx) * weightAt(x0, y0 + 1, m) + fx * weightAt(x0 + 1, y0 + 1, m));
                total += w[m];
            }
            // The weights' bytes sum to about 255; normalised, as MaterialSet::cover takes them.
            const double inverse = total > 0.0 ? 1.0 / total : 0.0;
            if (total <= 0.0) {
                w[0] = 1.0;
            }
            const std::size_t k = (static_cast<std::size_t>(j) * t + i) * 3;
            for (std::size_t ch = 0; ch < 3; ++ch) {
                const double map = rgb[k + ch] / 255.0;
                double sum = 0.0;
                for (std::size_t m = 0; m < count; ++m) {
                    sum += (total > 0.0 ? w[m] * inverse : w[m]) * (map * terms[m].scale[ch] + terms[m].offset[ch]);
                }
                out[k + ch] = static_cast<std::uint8_t>(std::lround(std::clamp(sum, 0.0, 1.0) * 255.0));
            }
        }
    }
    return out;
}

}  // namespace terrain
