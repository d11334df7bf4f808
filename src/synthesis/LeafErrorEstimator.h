// The error of static leaf nodes (paper 3.4.1, "Approximating Leaf Node Error"): how far the surface that
// detail synthesis adds below a static leaf (dynamic nodes: subdivision plus material displacement,
// DetailSynthesizer.h) deviates from the leaf's own surface. The exact value would need every descendant
// down to infinity, so it is estimated as the paper does, by stochastic sampling: a few random detail
// additions below the leaf, keeping the largest deviation found. prep used it for the map's detail_delta_c
// until the synthesis model (DetailErrorModel.h) replaced it; it stays as an independent
// reference for that model in the tests.
#pragma once

#include "synthesis/DetailSynthesizer.h"
#include "synthesis/DualHeightMap.h"

#include <cstdint>
#include <functional>
#include <span>

namespace terrain {

/// Random detail additions per static leaf: `descents` chains of dynamic nodes, each starting at a different
/// child of the leaf, each `depth` levels deep (random quadrants below the first level). Measured on the
/// bundled real terrain (trinidad 1025^2, 90 m, N 65, every one of its 256 leaves, grass + rock, kobbelt)
/// against the exhaustive reference over all 4 children and all 16 grandchildren (LeafErrorEstimatorTest),
/// with prep's CPU time (2 threads) relative to prep without the estimate, on that terrain and on
/// PrepBench's generated 4097^2 one (-h 10, steep enough that both materials are evaluated everywhere):
///
///   descents x depth   nodes per leaf   estimate / reference: mean, worst leaf   prep CPU: 1025^2, 4097^2
///   1 x 2              2                0.73, 0.08                               -
///   2 x 3              6                0.86, 0.19                               2.6 x, 3.1 x
///   3 x 2              6                0.95, 0.32                               -
///   4 x 1              4                0.993, 0.83                              2.2 x, 2.4 x
///   4 x 2              8                0.994, 0.85   <- the choice               3.3 x, 3.5 x
///   4 x 3              12               0.999, 0.85 (up to 1.26: deeper nodes)   4.3 x, 4.7 x
///
/// Most of a leaf's error comes from its first subdivision (the 4-point rule bending the leaf's triangles
/// where the terrain curves most), which lies in one quarter: a descent through one random child misses it
/// in most leaves, so every child is visited. Below each child one random grandchild adds the
/// displacement's next octave, which dominates on flat leaves. The exhaustive depth-2 reference itself
/// reaches 0.97 (mean) of a depth-3 one. By subdivision alone (no materials) the estimate equals the
/// reference; with Catmull-Clark, an approximating scheme whose surface keeps moving with depth, it reaches
/// 0.91 (mean).
inline constexpr int kLeafErrorDescents = 4;
inline constexpr int kLeafErrorDepth = 2;

struct LeafErrorSampling {
    int descents = kLeafErrorDescents;  ///< random descents from the leaf, 1..4, each through a different child
    int depth = kLeafErrorDepth;        ///< dynamic levels each descent goes down, >= 1
};

/// Estimates the largest vertical distance, in metres (>= 0), between the surface synthesized below a static
/// leaf and the leaf's own surface. `leaf.base` holds the leaf's W x W base heights (metres above the map's
/// height offset, rows south to north, W = synthesizer.windowSize()); its displacement is computed here as
/// for a node without a parent, so it need not be set. `where` places the leaf's window. The leaf is
/// displaced; then for each of `sampling.descents` distinct random children, a random chain of
/// `sampling.depth` dynamic descendants is synthesized (DetailSynthesizer::synthesizeChild), and each
/// one's N x N samples (base + displacement) are compared with the leaf's surface (base + displacement)
/// interpolated at the same positions along the template triangulation (quadtree/TemplateTriangulation.h,
/// the triangles the renderer draws). Returns the maximum found. The random choices come from `seed` only
/// (prep passes the node's key), so the result depends on the leaf and the seed, not on threads or order.
/// Thread-safe: the synthesizer is shared read-only.
float estimateLeafDetailError(DualHeightMap leaf, const WindowPlacement& where, const DetailSynthesizer& synthesizer,
                              std::uint64_t seed, const LeafErrorSampling& sampling = {});

}  // namespace terrain
