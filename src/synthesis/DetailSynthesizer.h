// Detail synthesis of dynamic nodes (paper 3.3, 3.4.3, 4.2.4): a child's base height field is subdivided
// from its parent's base (Subdivider.h), and a displacement height field from the materials (Material.h)
// is added on top (DualHeightMap.h). Static nodes get the same displacement, so a static leaf and the
// dynamic children below it nest exactly.
//
// Nesting and seams. A sample's displacement is the materials' fractals at its world position (SampleGrid),
// weighted by placement (slope, height, curvature, Material.h). The placement slope of a static node (displaced
// without a parent) is measured on its own base; a dynamic child interpolates its parent's slopes, so
// below the static leaves every sample keeps one placement at every depth and the synthesized surface
// converges to one continuous function (no sample carries weights from a coarser slope than its
// neighbours: tengine-tool error measured such spikes of up to 3 m of rock in grass). A dynamic child's even
// samples therefore copy the parent's displacement (the same inputs give the same value) and the others
// are evaluated. So (1) a dynamic child's even samples equal its parent's samples, base and displacement,
// and geomorphing to the parent's surface is exact; (2) two neighbouring nodes compute every shared sample
// from the same inputs with the same operations: bit-identical edges, no seams; (3) the result depends
// only on the node, not on the thread or the order of requests.
#pragma once

#include "core/Expected.h"
#include "quadtree/MapFormat.h"
#include "synthesis/DualHeightMap.h"
#include "synthesis/Fractal.h"
#include "synthesis/Material.h"
#include "synthesis/RoughnessNoise.h"
#include "synthesis/Subdivider.h"

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace terrain {

/// The detail_* options that shape synthesized geometry.
struct DetailSettings {
    std::string scheme = "kobbelt";  ///< detail_subdivision_scheme: kobbelt | bilinear | catmull-clark
    double omega = 1.0;              ///< detail_subdivision_factor, [0, 2]; kobbelt only
    /// detail_add_material: the materials whose displacement is added; null adds none (subdivision only).
    /// At most kMaxDetailMaterials materials (the renderer blends that many detail textures).
    std::shared_ptr<const MaterialSet> materials;
    /// detail_roughness with a map that measured its roughness: the terrain's own roughness
    /// continued below the static leaves (RoughnessNoise.h), added to the displacement of dynamic nodes.
    /// Null: none (detail_roughness off, or a map without a roughness block).
    std::shared_ptr<const RoughnessNoise> roughness = nullptr;
    /// The map's roughness laws (a RoughnessNoise made for the map: makeRoughnessNoise; only its laws are
    /// used here), whatever detail_roughness says: materials with a relative_amplitude follow them
    /// (materialScales). Null: every material has its absolute amplitude (a map without laws).
    std::shared_ptr<const RoughnessNoise> laws = nullptr;
};

/// Most materials a set may hold: their weights travel to the GPU as one RGBA8 value per sample.
inline constexpr std::size_t kMaxDetailMaterials = 4;

/// Whether synthesis keeps the weights the ground shows (DualHeightMap::weights) with a map.
enum class ShownWeights { Keep, Skip };

/// Where a node's window lies. Window sample (i, j) is at world x = originX + (gx0 + i) * spacing (and y
/// alike); its absolute height is heightOffset + base (the map's height offset: bases are stored relative
/// to it so float keeps millimetres).
struct WindowPlacement {
    double originX = 0.0;
    double originY = 0.0;
    double heightOffset = 0.0;
    double spacing = 1.0;  ///< metres between the node's samples, > 0
    std::int64_t gx0 = 0;  ///< global sample index at the node's level of window sample (0, 0)
    std::int64_t gy0 = 0;

    SampleGrid grid(int windowSize) const { return {originX, originY, gx0, gy0, spacing, windowSize, windowSize}; }
};

/// `settings` made for the map with `header` (the one rule shared by the viewer, height queries and prep's
/// leaf errors): with the map's roughness laws, the materials relativeTo its spacing, the laws made for them
/// (makeRoughnessNoise) set as `laws`, and as `roughness` too when `roughness` (detail_roughness); without
/// laws (no roughness block) the settings as they are, roughness and laws null.
DetailSettings settingsForMap(DetailSettings settings, const MapHeader& header, bool roughness);

/// Where node `id`'s window lies in the world of the map with header `h`: the one placement rule shared by
/// the viewer (lod/TerrainNodeSource.h), prep's detail error estimate (leafDetailErrorFunction) and height
/// queries.
WindowPlacement windowPlacement(const MapHeader& h, const NodeId& id);

/// Where child `quadrant` (bit 0 east, bit 1 north) of the node placed at `parent` lies: half the spacing,
/// global sample indices of the next level. `chunkSize` is N.
WindowPlacement childPlacement(const WindowPlacement& parent, int quadrant, int chunkSize);

class DetailSynthesizer {
public:
    /// Chunk size N (2^k + 1); an unknown scheme, omega outside [0, 2] or more than kMaxDetailMaterials
    /// materials is an error naming the option.
    static Expected<std::unique_ptr<const DetailSynthesizer>> create(int chunkSize, DetailSettings settings);

    int chunkSize() const { return mSubdivider->chunkSize(); }
    int windowSize() const { return terrain::windowSize(chunkSize()); }
    const DetailSettings& settings() const { return mSettings; }
    /// Whether nodes get a displacement field: materials, roughness or both.
    bool addsDisplacement() const { return mSettings.materials != nullptr || mSettings.roughness != nullptr; }
    bool addsMaterials() const { return mSettings.materials != nullptr; }

    /// Whether material m's amplitude follows the roughness laws (a relative material with laws).
    bool isRelative(std::size_t m) const { return m < mRelativeFactor.size() && mRelativeFactor[m] > 0.0; }
    /// Per material, the factor of its displacement over a window of `width` x `height` samples from global
    /// sample (gx0, gy0) of the level with spacing `spacing`: for a relative material relativeAmplitude x
    /// the law's deviation at its wavelength (RoughnessNoise::deviationGrid) / its fractalDeviation; empty for
    /// an absolute one (factor 1). Depends only on the position, like the displacement.
    std::vector<std::vector<float>> materialScales(std::int64_t gx0, std::int64_t gy0, int width, int height,
                                                   double spacing) const;
    /// materialScales over the node's N x N samples (its window's inner part).
    std::vector<std::vector<float>> nodeMaterialScales(const WindowPlacement& where) const;
    /// The most any material's displacement can be anywhere, metres: its amplitude, times the largest
    /// factor over the map for a relative one.
    double materialBound() const;

    /// How far the roughness noise can lie inside each cell of the level `levelsDown` below the node at `where`
    /// (over the node's square) from the template triangulation of its values at that level's samples: the
    /// octaves those samples lack, and the interpolation error of those they hold (RoughnessNoise::cellTails).
    /// out holds ((N - 1) 2^levelsDown)^2 values, rows south to north; zeros without roughness. metres.
    void roughnessTails(const WindowPlacement& where, int levelsDown, std::span<float> out) const;

    /// Sets map.displacement (and with several materials map.slope, map.weights and, where a material is placed
    /// by curvature, map.curvature) from map.base (W x W): with `parent` (a dynamic child: the parent's map, this
    /// node its child `quadrant`), the placement fields are the parent's interpolated and samples at even window
    /// positions copy the parent's displacement and weights, the others are evaluated; without (a static node),
    /// the fields come from map.base and every sample is evaluated. Clears them when no materials are set.
    /// With ShownWeights::Skip the map gets no weights (map.weights empty) and materials are evaluated only where
    /// the displacement weighs them: for maps only measured and dropped (bounds, normal maps' surfaces below,
    /// prep's estimates), whose descendants must skip them too.
    void displace(const WindowPlacement& where, const DualHeightMap* parent, int quadrant, DualHeightMap& map,
                  ShownWeights shown = ShownWeights::Keep) const;

    /// Child `quadrant`'s base heights from its parent's (W x W each): the subdivision step alone.
    void subdivideBase(std::span<const float> parent, int quadrant, std::span<float> child) const
    {
        mSubdivider->subdivide(parent, quadrant, child);
    }

    /// Dynamic child `quadrant` (0..3) of `parent`: base subdivided, then displace(). `where` places the child.
    DualHeightMap synthesizeChild(const DualHeightMap& parent, int quadrant, const WindowPlacement& where,
                                  ShownWeights shown = ShownWeights::Keep) const;
    /// The four dynamic children of the node `parent` placed at `where` (synthesizeChild of quadrants 0..3,
    /// each placed by childPlacement).
    std::array<DualHeightMap, 4> synthesizeChildren(const DualHeightMap& parent, const WindowPlacement& where,
                                                    ShownWeights shown = ShownWeights::Keep) const;

    /// The material weights of the node's N x N samples (border excluded), rows south to north, 4 bytes per
    /// sample: round(255 * weight of material m) for m < materials, the weights the ground shows (map.weights:
    /// blended by the materials' heights, not the displacement's: displacementWeights);
    /// empty when no materials are set. Precondition: `map` was displaced.
    std::vector<std::uint8_t> materialWeights(const DualHeightMap& map) const;
    /// The weights the displacement blends the materials with at the node's N x N samples, as materialWeights
    /// lays them out: from the placement fields alone (no height blending), so they are smooth where the
    /// fields are (what DetailErrorModel bounds finer levels' displacement with).
    std::vector<std::uint8_t> displacementWeights(const DualHeightMap& map, const WindowPlacement& where) const;

    /// Slope in degrees (0 flat) of the base at window sample (i, j): central differences, one-sided on
    /// the window's edge; within 0.001 degrees of the exact value (a polynomial arctangent).
    double slopeDegrees(const DualHeightMap& map, int i, int j, double spacing) const;

private:
    DetailSynthesizer(std::unique_ptr<Subdivider> subdivider, DetailSettings settings);
    /// The materials' part of displace(): placement slopes and the new samples' (all without a parent)
    /// material displacement. px0, py0: the parent window's sample under the child's (0, 0).
    void displaceByMaterials(const WindowPlacement& where, const DualHeightMap* parent, int px0, int py0,
                             bool keepWeights, std::span<const std::uint8_t> mask, DualHeightMap& map) const;

    std::unique_ptr<Subdivider> mSubdivider;
    DetailSettings mSettings;
    std::vector<std::uint8_t> mNewSamples;  ///< W x W: 1 where a child sample is not a parent sample
    std::vector<double> mRelativeFactor;    ///< per material: relativeAmplitude / fractalDeviation, or 0
};

/// A dynamic node's colour texture (3.4.5, before detail textures): its parent's texture over quadrant
/// `quadrant`, upsampled bilinearly to T x T RGB. Corner texels sit on the node's corners, so the child's
/// texel i lies at parent texel qx (T - 1) / 2 + i / 2 and neighbours share their edge texels.
/// Preconditions: T = 2^k + 1 >= 3, parent holds T * T * 3 bytes.
std::vector<std::uint8_t> upsampleTexture(std::span<const std::uint8_t> parent, int textureSize, int quadrant);

/// A node's ground colours: its map colours `rgb` (T x T RGB, corner texels on the node's corners) under the
/// materials (MaterialSet::cover) with the node's N x N `weights` (materialWeights: 4 bytes a sample),
/// interpolated bilinearly to each texel. Made when the node is made, so the fragments pay nothing for the
/// cover; the map colours stay apart (NodeData::mapTexture), since a child's come from its parent's and a cover
/// taken twice would compound. Preconditions: T >= 2, N >= 2, the sizes as stated.
std::vector<std::uint8_t> coverTexture(const MaterialSet& materials, std::span<const std::uint8_t> rgb, int textureSize,
                                       std::span<const std::uint8_t> weights, int chunkSize);

}  // namespace terrain
