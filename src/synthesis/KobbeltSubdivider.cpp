// Kobbelt's interpolatory 4-point rule, regular tensor-product case (Kobbelt 1996; paper 3.3.2, 3.4.3):
// quadtree/FourPointSubdivision.h in double for any omega, the stencil quadtree/HeightCodec.cpp predicts
// static nodes with. Built with -ffp-contract=off (src/synthesis/CMakeLists.txt): see the header's note on
// determinism.
#include "synthesis/KobbeltSubdivider.h"

#include "core/Check.h"
#include "quadtree/FourPointSubdivision.h"

#include <cmath>

namespace terrain {

void subdivideChildWindow(std::span<const float> parent, int chunkSize, int quadrant, double omega,
                          std::span<float> child)
{
    TERRAIN_EXPECTS(std::isfinite(omega), "omega must be finite");
    // Accumulated in double, the x pass kept in double, each child sample rounded to float once.
    subdivideFourPoint(parent, chunkSize, quadrant, fourPointWeights(omega), child,
                       [](double value) { return static_cast<float>(value); });
}

KobbeltSubdivider::KobbeltSubdivider(int chunkSize, double omega) : mChunkSize(chunkSize), mOmega(omega)
{
    TERRAIN_EXPECTS(isValidChunkSize(chunkSize), "chunk size must be 2^k + 1 in [3, 1025]");
    TERRAIN_EXPECTS(std::isfinite(omega), "omega must be finite");
}

void KobbeltSubdivider::subdivide(std::span<const float> parent, int quadrant, std::span<float> child) const
{
    subdivideChildWindow(parent, mChunkSize, quadrant, mOmega, child);
}

}  // namespace terrain
