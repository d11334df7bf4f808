#include "synthesis/DetailErrorModel.h"

#include "core/Check.h"
#include "core/SplitMix64.h"
#include "quadtree/NodeId.h"
#include "quadtree/TemplateTriangulation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>

namespace terrain {

namespace {

constexpr int kLevels = NodeId::kMaxLevel + 1;

/// Probe windows of the one-level change: (kChangeCells + 1)^2 samples at half the level's spacing.
constexpr int kChangeCells = 32;
constexpr int kChangeWindows = 24;
/// Probe windows of the deviation from the fine surface: kDeviationCells^2 cells of the level, each sampled
/// kDeviationSplit x kDeviationSplit times finer.
constexpr int kDeviationCells = 4;
constexpr int kDeviationSplit = 16;
constexpr int kDeviationWindows = 96;

/// Random window origins, even (so the window's even samples are samples of the coarser level) and far
/// from the lattice's origin in both directions.
std::int64_t randomOrigin(SplitMix64& random, std::int64_t multiple)
{
    return multiple * (static_cast<std::int64_t>(random.next() % (1u << 20)) - (1 << 19));
}

/// The largest change one level makes to `fractal` sampled at `spacing`: over probe windows at random places,
/// the fractal at the samples of spacing / 2 against the triangulated surface of the samples at `spacing`.
double oneLevelChange(const Fractal& fractal, double spacing, std::uint64_t seed, double& lowest, double& highest)
{
    const int fine = kChangeCells + 1;
    std::vector<float> values(static_cast<std::size_t>(fine) * fine);
    SplitMix64 random(seed);
    double worst = 0.0;
    for (int window = 0; window < kChangeWindows; ++window) {
        const std::int64_t gx0 = randomOrigin(random, 2), gy0 = randomOrigin(random, 2);
        fractal.evaluateGrid({0.0, 0.0, gx0, gy0, spacing * 0.5, fine, fine}, values);
        auto at = [&](int i, int j) { return static_cast<double>(values[static_cast<std::size_t>(j) * fine + i]); };
        for (float v : values) {
            lowest = std::min(lowest, static_cast<double>(v));
            highest = std::max(highest, static_cast<double>(v));
        }
        for (int j = 0; j < fine; ++j) {
            for (int i = (j & 1) ? 0 : 1; i < fine; i += (j & 1) ? 1 : 2) {
                double surface = 0.0;
                if ((i & 1) && (j & 1)) {
                    surface = 0.5 * (at(i - 1, j - 1) + at(i + 1, j + 1));  // the south-west to north-east diagonal
                } else if (i & 1) {
                    surface = 0.5 * (at(i - 1, j) + at(i + 1, j));
                } else {
                    surface = 0.5 * (at(i, j - 1) + at(i, j + 1));
                }
                worst = std::max(worst, std::abs(at(i, j) - surface));
            }
        }
    }
    return worst;
}

/// The largest distance between `fractal` sampled kDeviationSplit times finer than `spacing` and the
/// triangulated surface of its samples at `spacing`, over probe windows at random places.
double deviationFromFiner(const Fractal& fractal, double spacing, std::uint64_t seed)
{
    const int fine = kDeviationCells * kDeviationSplit + 1;
    std::vector<float> values(static_cast<std::size_t>(fine) * fine);
    SplitMix64 random(seed);
    double worst = 0.0;
    for (int window = 0; window < kDeviationWindows; ++window) {
        const std::int64_t gx0 = randomOrigin(random, kDeviationSplit), gy0 = randomOrigin(random, kDeviationSplit);
        fractal.evaluateGrid({0.0, 0.0, gx0, gy0, spacing / kDeviationSplit, fine, fine}, values);
        auto at = [&](int i, int j) { return static_cast<double>(values[static_cast<std::size_t>(j) * fine + i]); };
        for (int cy = 0; cy < kDeviationCells; ++cy) {
            for (int cx = 0; cx < kDeviationCells; ++cx) {
                const int i0 = cx * kDeviationSplit, j0 = cy * kDeviationSplit;
                const double h00 = at(i0, j0), h10 = at(i0 + kDeviationSplit, j0);
                const double h01 = at(i0, j0 + kDeviationSplit), h11 = at(i0 + kDeviationSplit, j0 + kDeviationSplit);
                for (int b = 0; b <= kDeviationSplit; ++b) {
                    for (int a = 0; a <= kDeviationSplit; ++a) {
                        const double surface = interpolateQuad(h00, h10, h01, h11, a / double(kDeviationSplit),
                                                               b / double(kDeviationSplit));
                        worst = std::max(worst, std::abs(at(i0 + a, j0 + b) - surface));
                    }
                }
            }
        }
    }
    return worst;
}

}  // namespace

DetailErrorModel::DetailErrorModel(const DetailSynthesizer& synthesizer, double rootSpacing)
    : mSynthesizer(synthesizer), mRootSpacing(rootSpacing)
{
    TERRAIN_EXPECTS(rootSpacing > 0.0 && std::isfinite(rootSpacing), "the root spacing must be > 0");
    if (!synthesizer.settings().materials) {
        return;
    }
    const auto& materials = synthesizer.settings().materials->materials();
    mMaterials.resize(materials.size());
    for (std::size_t m = 0; m < materials.size(); ++m) {
        const Material& material = materials[m];
        PerMaterial& pm = mMaterials[m];
        pm.error.assign(kLevels, std::numeric_limits<double>::quiet_NaN());
        if (!material.displacement) {
            std::fill(pm.error.begin(), pm.error.end(), 0.0);
            continue;
        }
        const double amplitude = material.fractal.amplitude;
        const std::uint64_t seed = material.fractal.seed * 1000003u;
        // tail[level]: the one-level changes of `level` and every finer level, summed (a bound on what the
        // levels below add, since each adds at most its largest change).
        double lowest = amplitude, highest = -amplitude;  // the fractal's values over every probe
        pm.tail.assign(kLevels + 1, 0.0);
        for (int level = kLevels - 1; level >= 0; --level) {
            const auto l = static_cast<std::size_t>(level);
            const double change = pm.tail[l + 1] < 1e-6 * amplitude && level + 12 < kLevels
                                      ? 0.0  // far below anything a node can show, and the fractal is smooth there
                                      : oneLevelChange(*material.displacement, std::ldexp(rootSpacing, -level),
                                                       seed + static_cast<std::uint64_t>(level), lowest, highest);
            pm.tail[l] = pm.tail[l + 1] + change;
        }
        // A triangle's interpolation lies within the fractal's range, so no level errs by more than the range
        // (measured, with the margin; and never more than 2 amplitude, where |f| <= amplitude puts it).
        pm.range = std::min(2.0 * amplitude, kDisplacementMargin * (highest - lowest));
    }
}

double DetailErrorModel::nextSubdivisionChange(const DualHeightMap& heights) const
{
    std::vector<float> cells;
    return nextSubdivisionChanges(heights, cells);
}

double DetailErrorModel::nextSubdivisionChanges(const DualHeightMap& heights, std::vector<float>& cells) const
{
    const int n = mSynthesizer.chunkSize();
    const int w = mSynthesizer.windowSize();
    TERRAIN_EXPECTS(heights.size == w && heights.base.size() == static_cast<std::size_t>(w) * w,
                    "the node's window does not match the synthesizer's chunk size");
    std::vector<float> child(static_cast<std::size_t>(w) * w);
    const int half = (n - 1) / 2;
    auto base = [&](int i, int j) {
        return static_cast<double>(heights.base[static_cast<std::size_t>(j + kBorder) * w + i + kBorder]);
    };
    cells.assign(static_cast<std::size_t>(n - 1) * (n - 1), 0.0f);
    double worst = 0.0;
    for (int q = 0; q < 4; ++q) {
        mSynthesizer.subdivideBase(heights.base, q, child);
        const int x0 = (q & 1) * half, y0 = (q >> 1) * half;
        // Child sample (a, b) lies at node position (x0 + a / 2, y0 + b / 2), in node cell (i, j) (the last
        // row and column of samples in the cell before them).
        for (int b = 0; b < n; ++b) {
            for (int a = 0; a < n; ++a) {
                const int i = std::min(x0 + a / 2, n - 2), j = std::min(y0 + b / 2, n - 2);
                const double fx = (x0 + a * 0.5) - i, fy = (y0 + b * 0.5) - j;
                const double surface =
                    interpolateQuad(base(i, j), base(i + 1, j), base(i, j + 1), base(i + 1, j + 1), fx, fy);
                const double z = child[static_cast<std::size_t>(b + kBorder) * w + a + kBorder];
                const auto change = static_cast<float>(std::abs(z - surface));
                float& cell = cells[static_cast<std::size_t>(j) * (n - 1) + i];
                cell = std::max(cell, change);
                worst = std::max(worst, static_cast<double>(change));
            }
        }
    }
    return worst;
}

double DetailErrorModel::displacementError(std::size_t m, int level) const
{
    TERRAIN_EXPECTS(level >= 0 && level <= NodeId::kMaxLevel, "level out of range");
    if (m >= mMaterials.size()) {
        return 0.0;
    }
    const PerMaterial& pm = mMaterials[m];
    const auto l = static_cast<std::size_t>(level);
    std::lock_guard lock(mMutex);  // levels are measured when first asked for: the same value whoever asks
    if (std::isnan(pm.error[l])) {
        const Material& material = mSynthesizer.settings().materials->materials()[m];
        const double amplitude = material.fractal.amplitude;
        constexpr int kFinerLevels = 4;  // log2(kDeviationSplit): what deviationFromFiner covers
        static_assert((1 << kFinerLevels) == kDeviationSplit);
        // The deviation from the surface kDeviationSplit times finer, measured in one piece (not a sum of
        // per-level maxima, which are reached at different places), plus what the levels below that add.
        const std::size_t below = std::min<std::size_t>(l + kFinerLevels, kLevels);
        const double deviation =
            pm.tail[l] < 1e-7 * amplitude
                ? pm.tail[l]
                : std::min(pm.tail[l], deviationFromFiner(*material.displacement, std::ldexp(mRootSpacing, -level),
                                                          material.fractal.seed * 1000003u + 7919u * (l + 1)) +
                                           pm.tail[below]);
        pm.error[l] = std::min(pm.range, kDisplacementMargin * deviation);
    }
    return pm.error[l];
}

double DetailErrorModel::worstDisplacementError(int level) const
{
    double worst = 0.0;
    for (std::size_t m = 0; m < mMaterials.size(); ++m) {
        worst = std::max(worst, displacementError(m, level));
    }
    return worst;
}

std::vector<double> DetailErrorModel::sampleDisplacementErrors(std::span<const std::uint8_t> weights, int level,
                                                               std::span<const std::vector<float>> scales) const
{
    const int n = mSynthesizer.chunkSize();
    const std::size_t count = mMaterials.size();
    std::vector<double> sample(static_cast<std::size_t>(n) * n, 0.0);
    TERRAIN_EXPECTS(scales.empty() || scales.size() == count, "one scale grid (or none) per material");
    auto scale = [&](std::size_t m, std::size_t k) {
        return scales.empty() || scales[m].empty() ? 1.0 : static_cast<double>(scales[m][k]);
    };
    if (count == 1) {
        const double error = displacementError(0, level);
        for (std::size_t k = 0; k < sample.size(); ++k) {
            sample[k] = error * scale(0, k);
        }
    } else if (count > 1) {
        TERRAIN_EXPECTS(weights.size() == sample.size() * 4, "weights must hold N x N x 4 bytes");
        std::array<double, kMaxDetailMaterials> error{};
        for (std::size_t m = 0; m < count; ++m) {
            error[m] = displacementError(m, level) / 255.0;
        }
        for (std::size_t k = 0; k < sample.size(); ++k) {
            for (std::size_t m = 0; m < count; ++m) {
                // Half a step: the weights are rounded.
                sample[k] += (weights[4 * k + m] + 0.5) * error[m] * scale(m, k);
            }
        }
    }
    return sample;
}

double DetailErrorModel::displacementTerm(std::span<const std::uint8_t> weights, int level,
                                          std::span<const std::vector<float>> scales) const
{
    const std::vector<double> sample = sampleDisplacementErrors(weights, level, scales);
    return *std::max_element(sample.begin(), sample.end());
}

void DetailErrorModel::descendantCellBounds(const DualHeightMap& node, const DualHeightMap& descendant,
                                            const WindowPlacement& at, int descendantLevel, double x0, double y0,
                                            double step, std::vector<double>& out) const
{
    const int n = mSynthesizer.chunkSize();
    const int w = mSynthesizer.windowSize();
    TERRAIN_EXPECTS(descendant.size == w && descendant.base.size() == node.base.size(),
                    "a descendant's window is not W x W");
    auto surface = [&](const DualHeightMap& map, int i, int j) {
        return static_cast<double>(map.height(static_cast<std::size_t>(j + kBorder) * w + i + kBorder));
    };
    // Descendant sample (a, b) lies at node position (x0 + a step, y0 + b step), in node cell (i, j).
    std::vector<double> measured(static_cast<std::size_t>(n) * n);
    for (int b = 0; b < n; ++b) {
        for (int a = 0; a < n; ++a) {
            const double x = x0 + a * step, y = y0 + b * step;
            const int i = std::min(static_cast<int>(x), n - 2), j = std::min(static_cast<int>(y), n - 2);
            const double own = interpolateQuad(surface(node, i, j), surface(node, i + 1, j), surface(node, i, j + 1),
                                               surface(node, i + 1, j + 1), x - i, y - j);
            measured[static_cast<std::size_t>(b) * n + a] = std::abs(surface(descendant, a, b) - own);
        }
    }
    std::vector<float> changes;
    nextSubdivisionChanges(descendant, changes);
    const std::vector<double> displacement = sampleDisplacementErrors(
        mSynthesizer.displacementWeights(descendant, at), descendantLevel, mSynthesizer.nodeMaterialScales(at));
    std::vector<float> roughness(static_cast<std::size_t>(n - 1) * (n - 1));
    mSynthesizer.roughnessTails(at, 0, roughness);
    out.resize(static_cast<std::size_t>(n - 1) * (n - 1));
    for (int b = 0; b + 1 < n; ++b) {
        for (int a = 0; a + 1 < n; ++a) {
            auto corners = [&](const std::vector<double>& v) {
                auto get = [&](int x, int y) { return v[static_cast<std::size_t>(y) * n + x]; };
                return std::max({get(a, b), get(a + 1, b), get(a, b + 1), get(a + 1, b + 1)});
            };
            const std::size_t c = static_cast<std::size_t>(b) * (n - 1) + a;
            out[c] = corners(measured) + kSubdivisionTail * changes[c] + corners(displacement) + roughness[c];
        }
    }
}

float DetailErrorModel::boundFromChildren(const DualHeightMap& node, const std::array<DualHeightMap, 4>& children,
                                          const WindowPlacement& where, int level) const
{
    TERRAIN_EXPECTS(level >= 0 && level < NodeId::kMaxLevel, "the children's level must exist");
    const int n = mSynthesizer.chunkSize();
    const int w = mSynthesizer.windowSize();
    TERRAIN_EXPECTS(node.size == w && node.base.size() == static_cast<std::size_t>(w) * w,
                    "the node's window does not match the synthesizer's chunk size");
    const int half = (n - 1) / 2;
    const auto cellCount = static_cast<std::size_t>(n - 1) * (n - 1);
    // Per child, the bound of each of its cells from its samples.
    std::array<std::vector<double>, 4> bounds;
    for (int q = 0; q < 4; ++q) {
        descendantCellBounds(node, children[static_cast<std::size_t>(q)], childPlacement(where, q, n), level + 1,
                             (q & 1) * half, (q >> 1) * half, 0.5, bounds[static_cast<std::size_t>(q)]);
    }
    // Where the bound peaks, one level deeper: the grandchild holding the worst cell is synthesized and each
    // child cell it covers takes the smaller of its two bounds (both hold; the grandchildren's samples are
    // exact too, and their tail is smaller), until the worst cell is one already refined. DetailBoundTest's
    // medians of measured / bound rise from 0.5-0.7 to 0.7-0.9 with it; DynamicNodeBench: +50% a node.
    std::array<bool, 16> refined{};
    std::vector<double> fine;
    for (;;) {
        int worstQ = 0;
        std::size_t worstCell = 0;
        for (int q = 0; q < 4; ++q) {
            const std::vector<double>& v = bounds[static_cast<std::size_t>(q)];
            const auto it = std::max_element(v.begin(), v.end());
            if (*it > bounds[static_cast<std::size_t>(worstQ)][worstCell]) {
                worstQ = q;
                worstCell = static_cast<std::size_t>(it - v.begin());
            }
        }
        const int a = static_cast<int>(worstCell % static_cast<std::size_t>(n - 1));
        const int b = static_cast<int>(worstCell / static_cast<std::size_t>(n - 1));
        const int g = (a >= half ? 1 : 0) + (b >= half ? 2 : 0);
        if (level + 2 > NodeId::kMaxLevel || refined[static_cast<std::size_t>(worstQ * 4 + g)]) {
            break;
        }
        refined[static_cast<std::size_t>(worstQ * 4 + g)] = true;
        const WindowPlacement childAt = childPlacement(where, worstQ, n);
        const WindowPlacement at = childPlacement(childAt, g, n);
        const DualHeightMap grandchild =
            mSynthesizer.synthesizeChild(children[static_cast<std::size_t>(worstQ)], g, at, ShownWeights::Skip);
        const double gx0 = (worstQ & 1) * half + (g & 1) * half * 0.5;
        const double gy0 = (worstQ >> 1) * half + (g >> 1) * half * 0.5;
        descendantCellBounds(node, grandchild, at, level + 2, gx0, gy0, 0.25, fine);
        // Child cell (a, b) of the grandchild's quarter covers grandchild cells 2 (a - a0) + {0, 1}, likewise b.
        std::vector<double>& coarse = bounds[static_cast<std::size_t>(worstQ)];
        const int a0 = (g & 1) * half, b0 = (g >> 1) * half;
        for (int cb = 0; cb < half; ++cb) {
            for (int ca = 0; ca < half; ++ca) {
                double deeper = 0.0;
                for (int k = 0; k < 4; ++k) {
                    const int fa = 2 * ca + (k & 1), fb = 2 * cb + (k >> 1);
                    deeper = std::max(deeper, fine[static_cast<std::size_t>(fb) * (n - 1) + fa]);
                }
                double& cell = coarse[static_cast<std::size_t>(b0 + cb) * (n - 1) + a0 + ca];
                cell = std::min(cell, deeper);
            }
        }
    }
    double worst = 0.0;
    for (const std::vector<double>& v : bounds) {
        worst = std::max(worst, *std::max_element(v.begin(), v.end()));
    }
    TERRAIN_ASSERT(bounds[0].size() == cellCount);
    // The samples are floats: the node's, the descendants' and every later level's each round by half a unit
    // in the last place of the largest height, and the displacement's sum once more.
    double largest = 0.0;
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            largest = std::max(
                largest,
                std::abs(static_cast<double>(node.height(static_cast<std::size_t>(j + kBorder) * w + i + kBorder))));
        }
    }
    return static_cast<float>(worst + kFloatRounding * largest);
}

std::function<float(const MapHeader&, const NodeId&, std::span<const std::uint16_t>)> leafDetailErrorFunction(
    const DetailSynthesizer& synthesizer, bool roughness)
{
    // What the viewer synthesizes over this map (settingsForMap: relative materials follow its laws), made on
    // the first call for the map's spacing and laws.
    struct ForMap {
        std::unique_ptr<const DetailSynthesizer> synthesizer;
        std::unique_ptr<const DetailErrorModel> model;
    };
    struct Shared {
        std::mutex mutex;
        double rootSpacing = 0.0;
        const RoughnessGrid* grid = nullptr;  ///< the header's grid the synthesizer was made for
        std::shared_ptr<const ForMap> forMap;
    };
    auto shared = std::make_shared<Shared>();
    return [&synthesizer, shared, roughness](const MapHeader& h, const NodeId& id,
                                             std::span<const std::uint16_t> codes) {
        std::shared_ptr<const ForMap> forMap;
        {
            std::lock_guard lock(shared->mutex);
            const RoughnessGrid* grid = h.roughness ? &*h.roughness : nullptr;
            if (!shared->forMap || shared->rootSpacing != h.spacingAt(0) || shared->grid != grid) {
                auto made = DetailSynthesizer::create(synthesizer.chunkSize(),
                                                      settingsForMap(synthesizer.settings(), h, roughness));
                TERRAIN_ASSERT(made.ok());  // the same settings the given synthesizer was made with
                auto next = std::make_shared<ForMap>();
                next->synthesizer = std::move(made).value();
                next->model = std::make_unique<const DetailErrorModel>(*next->synthesizer, h.spacingAt(0));
                shared->forMap = std::move(next);
                shared->rootSpacing = h.spacingAt(0);
                shared->grid = grid;
            }
            forMap = shared->forMap;
        }
        const DetailSynthesizer& s = *forMap->synthesizer;
        DualHeightMap leaf;
        leaf.size = h.windowSize();
        leaf.base.resize(codes.size());
        for (std::size_t k = 0; k < codes.size(); ++k) {
            leaf.base[k] = static_cast<float>(h.heightStep * codes[k]);  // as TerrainNodeSource::loadStatic makes it
        }
        const WindowPlacement where = windowPlacement(h, id);
        s.displace(where, nullptr, 0, leaf, ShownWeights::Skip);
        // The leaf's children as the viewer synthesizes them below it, measured, plus the model's tail.
        return forMap->model->boundFromChildren(leaf, s.synthesizeChildren(leaf, where, ShownWeights::Skip), where,
                                                id.level);
    };
}

double detailDisplacementRange(const DetailSynthesizer& synthesizer)
{
    return 2.0 * synthesizer.materialBound();
}

std::function<double(const MapHeader&)> detailDisplacementRangeFunction(const DetailSynthesizer& synthesizer)
{
    return [&synthesizer](const MapHeader& h) {
        auto made =
            DetailSynthesizer::create(synthesizer.chunkSize(), settingsForMap(synthesizer.settings(), h, false));
        TERRAIN_ASSERT(made.ok());
        return detailDisplacementRange(**made);
    };
}

}  // namespace terrain
