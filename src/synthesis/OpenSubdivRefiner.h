// `detail_subdivision_scheme = bilinear | catmull-clark` through OpenSubdiv's Far API (3.5): one uniform
// refinement step of the parent's heights as a quad mesh, cut into the child's window.
#pragma once

#include "synthesis/Subdivider.h"

#include <memory>
#include <span>
#include <vector>

namespace terrain {

enum class OpenSubdivScheme {
    Bilinear,      ///< Sdc::SCHEME_BILINEAR: interpolating, equals KobbeltSubdivider with omega = 0
    CatmullClark,  ///< Sdc::SCHEME_CATMARK: approximating (the parent's samples move), C2 in the limit
};

/// A Subdivider that refines with OpenSubdiv. The topology of every child computation is the same, so the
/// Far::TopologyRefiner is built once, in the constructor; subdivide() only interpolates (Far::
/// PrimvarRefiner, double weights and values, rounded to float once), so it is const and thread-safe.
///
/// What is refined: not the whole parent window but the M x M parent samples, M = (N + 9) / 2, starting at
/// parent window index qx (N - 1) / 2 (and the same in y). Its level-1 refinement has the child's W x W
/// window at refined index 2 (one parent sample in from the edge), so every child sample, border included,
/// gets the regular interior rules from parent samples inside the window: no extrapolation, no fallback,
/// and the mesh boundary's special rules never reach a child sample. Children of neighbouring parents that
/// agree on their shared window samples therefore agree on their shared samples (bit for bit: the regular
/// stencils are applied in the same order at every grid position).
///
/// Catmull-Clark is approximating: a child's even samples are smoothed parent samples, not copies, so the
/// nesting "a parent's samples are its children's even samples" does not hold and geomorphing to the
/// parent's surface shows a small offset. It is offered for comparison; kobbelt is the default.
class OpenSubdivRefiner final : public Subdivider {
public:
    /// Builds the refiner for chunk size N (2^k + 1).
    OpenSubdivRefiner(int chunkSize, OpenSubdivScheme scheme);
    ~OpenSubdivRefiner() override;
    OpenSubdivRefiner(const OpenSubdivRefiner&) = delete;
    OpenSubdivRefiner& operator=(const OpenSubdivRefiner&) = delete;

    int chunkSize() const override { return mChunkSize; }
    OpenSubdivScheme scheme() const { return mScheme; }
    void subdivide(std::span<const float> parent, int quadrant, std::span<float> child) const override;

private:
    int mChunkSize;
    OpenSubdivScheme mScheme;
    int mPatchSize;   ///< M: parent samples per side of the refined patch
    struct Topology;  ///< the Far::TopologyRefiner, kept out of this header
    std::unique_ptr<const Topology> mTopology;
    int mRefinedCount;                 ///< vertices of refinement level 1
    std::vector<int> mChildToRefined;  ///< child window sample (row-major, W * W) -> level-1 vertex
};

}  // namespace terrain
