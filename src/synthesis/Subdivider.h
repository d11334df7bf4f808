// The subdivision step of dynamic nodes (paper 3.3.2, 3.4.3): a child's base height window from its
// parent's. One interface, three schemes picked by `detail_subdivision_scheme`:
//   kobbelt        Kobbelt's interpolatory 4-point rule, tensor product (KobbeltSubdivider.h); the default,
//                  and the stencil of the static nodes' residual predictor (quadtree/FourPointSubdivision.h).
//   bilinear       OpenSubdiv's bilinear scheme (OpenSubdivRefiner.h); equals kobbelt with omega = 0.
//   catmull-clark  OpenSubdiv's Catmull-Clark scheme: smoother (C2 in the limit) but approximating, so the
//                  parent's samples move and a child's even samples are not its parent's.
//
// Window geometry (quadtree/ChunkGeometry.h, 3.4.3 "Borders"): a node's heights are W = N + 4 samples per
// side (N = chunk size 2^k + 1, a border of kBorder = 2 samples on each side), row-major, rows south
// to north, x east. Child `quadrant` (bit 0: east half, bit 1: north half) covers a quarter of its parent
// at twice the density.
#pragma once

#include "core/Expected.h"
#include "quadtree/ChunkGeometry.h"

#include <memory>
#include <span>
#include <string_view>

namespace terrain {

/// Computes a child's base height window from its parent's. Implementations are immutable after
/// construction: one instance per (chunk size, scheme) is shared by all worker threads, and the same
/// inputs give bit-identical outputs on any thread and in any order.
class Subdivider {
public:
    virtual ~Subdivider() = default;

    /// Samples per node side (N) this subdivider was made for.
    virtual int chunkSize() const = 0;

    /// Writes child `quadrant`'s (0..3) window into `child` from `parent`. Both spans hold W * W heights in
    /// metres (W = windowSize(chunkSize())) and must not overlap. Sibling and cousin children (whose parents
    /// agree on their overlapping window samples) get bit-identical values on every sample they share.
    virtual void subdivide(std::span<const float> parent, int quadrant, std::span<float> child) const = 0;
};

/// Makes the subdivider for `scheme` ("kobbelt", "bilinear" or "catmull-clark", the values of
/// `detail_subdivision_scheme`) and chunk size N (2^k + 1). `omega` (`detail_subdivision_factor`, finite, in
/// [0, 2]) is used by kobbelt only. An unknown scheme name is an error naming the value and the choices.
Expected<std::unique_ptr<Subdivider>> makeSubdivider(std::string_view scheme, int chunkSize, double omega);

}  // namespace terrain
