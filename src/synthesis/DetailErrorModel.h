// The error of synthesized detail from the synthesis model (paper 3.4.1, replacing "half the error
// of the parent"): how far the surface synthesized below a node (DetailSynthesizer.h: subdivision of the base
// plus material displacement and the roughness continued) can lie from the node's own triangulated surface:
//
//   delta = max over the children's cells of  max over the cell's corners of |child sample - node surface|
//           + kSubdivisionTail * D1(cell) + max over the cell's corners of sum_m w_m * E_m(level + 1)
//           + the roughness octaves' tail
//
// The first term is measured on the node's four children, made on the worker thread with the node (they
// are the samples its normal map shades with): a sample never moves at finer levels (the subdivision is
// interpolatory, the materials' displacement depends on the position only, the roughness octaves below
// vanish there), so at the children's samples the node's error is known exactly, and since the children's
// triangles nest in the node's, it is exact on every cell's corners. What is left to bound is how far the
// limit surface lies from the children's triangles inside each cell, the three terms after it:
//
// - D1: the largest change the next subdivision makes to the base (every grandchild sample against the
//   child's surface along the template triangulation), computed from the children's bases. Later levels
//   change it less: the 4-point rule's changes shrink by 1/4 per level on smooth data, so the whole tail is
//   D1 / (1 - 1/4).
//   (Measured on the bundled terrain with tengine-tool error --levels: the largest distance of a node from
//   the reference is up to 1.0 D1, so 4/3 holds with margin; a contraction of only 1/2 would need 2.)
// - E_m(level): how far material m's displacement, sampled at the level's spacing and interpolated along the
//   triangles, can lie from its limit: measured once per material and level on windows of the fractal
//   itself at random places, as the largest distance of the fractal sampled 16 times finer from the
//   level's triangles, plus the largest change each level below that makes, times kDisplacementMargin, and
//   never more than the fractal's range (measured on the probes, times the margin; at most 2 amplitude). It
//   shrinks by the fractal's gain per level while octaves are finer than the spacing, then by 4 per level once
//   the sampling resolves them all (fBm); a ridged fractal's creases keep it shrinking by about 2.
// - w_m: material m's weight at a sample (placement, DetailSynthesizer::displacementWeights): the displacement
//   there is the weighted sum of the materials', so its error is the weighted sum of theirs.
// - the roughness octaves (RoughnessNoise::cellTails, per child cell): those the children lack, up to the
//   noise's measured peak each, and the interpolation error of those they hold between their samples
//   (PerlinNoise::extremes).
//
// The viewer computes it for every dynamic node it makes (lod/TerrainNodeSource.h) and prep for every static
// leaf (leafDetailErrorFunction), so both follow one model; tengine-tool error measures how tight it is, and
// DetailBoundTest checks it against the nodes' descendants synthesized three levels down.
#pragma once

#include "synthesis/DetailSynthesizer.h"

#include <array>
#include <cstdint>
#include <functional>
#include <mutex>
#include <span>
#include <vector>

namespace terrain {

class DetailErrorModel {
public:
    static constexpr double kSubdivisionTail = 4.0 / 3.0;
    static constexpr double kDisplacementMargin = 1.25;
    /// The float rounding of a node's samples and of every level's below it, relative to the largest height:
    /// four units of 2^-24 (two samples' rounding and the displacement's sum, with a unit to spare).
    static constexpr double kFloatRounding = 4.0 / (1 << 24);

    /// The model for `synthesizer` (which must outlive it) on a quadtree whose level 0 has sample spacing
    /// `rootSpacing` metres (level k: rootSpacing / 2^k). Measures the per-level changes of every material
    /// (tens of milliseconds); each level's E_m is measured when first asked for (thread-safe).
    DetailErrorModel(const DetailSynthesizer& synthesizer, double rootSpacing);

    /// D1 of a node's base heights (W x W window, metres): the largest distance from the node's surface of the
    /// base samples its four children get (the synthesizer's own subdivider), over the node's square.
    double nextSubdivisionChange(const DualHeightMap& heights) const;
    /// The same, and per cell of the node ((N - 1)^2, rows south to north) the largest change of the child
    /// samples in it (on its edges included) into `cells`.
    double nextSubdivisionChanges(const DualHeightMap& heights, std::vector<float>& cells) const;

    /// E_m at quadtree `level` (metres), material `m` in the synthesizer's order; 0 without materials.
    double displacementError(std::size_t m, int level) const;

    /// max over samples of sum_m w_m E_m(level) for a node with `weights` (DetailSynthesizer::displacementWeights:
    /// N x N x 4 bytes; empty when there are no materials).
    /// With `scales` (DetailSynthesizer::nodeMaterialScales), material m's error at a sample is times
    /// scales[m] there where that is not empty (relative materials).
    double displacementTerm(std::span<const std::uint8_t> weights, int level,
                            std::span<const std::vector<float>> scales = {}) const;

    /// The bound of the node at `level` placed at `where` with window `node`, from its four children
    /// (DetailSynthesizer::synthesizeChildren): over every cell of the children, the largest distance of its
    /// corners (the children's samples: the limit surface there, for no later level moves them) from the
    /// node's triangulated surface, measured, plus what the levels below the children can add inside the
    /// cell: kSubdivisionTail x the children's next subdivision change there, the materials' E_m(level + 1)
    /// at its corners weighted by placement (relative materials scaled), and the roughness octaves
    /// (DetailSynthesizer::roughnessTails, per cell). Where that peaks, the same one level deeper: the
    /// grandchild under the worst cell is synthesized and each cell it covers takes the smaller bound, until the
    /// worst cell is one already refined.
    /// Plus kFloatRounding x the largest |height|. Descendants' triangles nest in the node's, so the measured
    /// part is exact over each cell and only the tail is a model. metres.
    float boundFromChildren(const DualHeightMap& node, const std::array<DualHeightMap, 4>& children,
                            const WindowPlacement& where, int level) const;

    /// The largest E_m(level) over the materials: the displacement term of a node whose weights are unknown.
    double worstDisplacementError(int level) const;

private:
    /// The bound of each cell ((N - 1)^2, rows south to north) of a descendant of `node` (its window, placed at
    /// `at`, at quadtree level `descendantLevel`) whose sample (a, b) lies at node sample position (x0 + a step,
    /// y0 + b step): its corners' distance from the node's triangulated surface, measured, plus the tail of the
    /// levels below it inside the cell (see boundFromChildren), into `out`.
    void descendantCellBounds(const DualHeightMap& node, const DualHeightMap& descendant, const WindowPlacement& at,
                              int descendantLevel, double x0, double y0, double step, std::vector<double>& out) const;
    /// Per sample of the node (N x N), sum_m w_m E_m(level).
    std::vector<double> sampleDisplacementErrors(std::span<const std::uint8_t> weights, int level,
                                                 std::span<const std::vector<float>> scales) const;

    struct PerMaterial {
        std::vector<double> tail;           ///< per level: the one-level changes of it and every finer level
        double range = 0.0;                 ///< the largest any level's error can be
        mutable std::vector<double> error;  ///< E_m per level, NaN until first asked for (under mMutex)
    };
    const DetailSynthesizer& mSynthesizer;
    double mRootSpacing;
    std::vector<PerMaterial> mMaterials;
    mutable std::mutex mMutex;
};

/// QuadtreeBuilder's leafDetailError for `synthesizer` (paper 3.4.1, with this model): the leaf's codes as
/// the viewer's base heights, displaced and placed as the viewer does a static node (windowPlacement), and
/// DetailErrorModel::bound at the leaf's level; with `roughness` and a header with a roughness grid, plus the
/// most the roughness octaves below the leaf add (makeRoughnessNoise, RoughnessNoise::bound). Thread-safe;
/// the model is made on the first call for the map's spacing. `synthesizer` must outlive the returned function.
std::function<float(const MapHeader&, const NodeId&, std::span<const std::uint16_t>)> leafDetailErrorFunction(
    const DetailSynthesizer& synthesizer, bool roughness = false);

/// QuadtreeBuilder's detailDisplacementRange: 2 x the largest amplitude of the synthesizer's materials
/// (DetailSynthesizer::materialBound).
double detailDisplacementRange(const DetailSynthesizer& synthesizer);
/// QuadtreeBuilder's detailDisplacementRangeFor: detailDisplacementRange of the synthesizer made for the map
/// (settingsForMap: relative materials follow its roughness laws).
std::function<double(const MapHeader&)> detailDisplacementRangeFunction(const DetailSynthesizer& synthesizer);

}  // namespace terrain
