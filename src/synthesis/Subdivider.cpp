// The `detail_subdivision_scheme` factory (paper 3.3.2: Kobbelt's scheme; bilinear and Catmull-Clark
// through OpenSubdiv for comparison).
#include "synthesis/Subdivider.h"

#include "core/Check.h"
#include "synthesis/KobbeltSubdivider.h"
#include "synthesis/OpenSubdivRefiner.h"

#include <cmath>

namespace terrain {

Expected<std::unique_ptr<Subdivider>> makeSubdivider(std::string_view scheme, int chunkSize, double omega)
{
    TERRAIN_EXPECTS(isValidChunkSize(chunkSize), "chunk size must be 2^k + 1 in [3, 1025]");
    TERRAIN_EXPECTS(std::isfinite(omega) && omega >= 0.0 && omega <= 2.0, "omega must be in [0, 2]");
    std::unique_ptr<Subdivider> subdivider;
    if (scheme == "kobbelt") {
        subdivider = std::make_unique<KobbeltSubdivider>(chunkSize, omega);
    } else if (scheme == "bilinear") {
        subdivider = std::make_unique<OpenSubdivRefiner>(chunkSize, OpenSubdivScheme::Bilinear);
    } else if (scheme == "catmull-clark") {
        subdivider = std::make_unique<OpenSubdivRefiner>(chunkSize, OpenSubdivScheme::CatmullClark);
    } else {
        return makeError("detail_subdivision_scheme: unknown scheme '", scheme,
                         "' (expected kobbelt, bilinear or catmull-clark)");
    }
    return subdivider;
}

}  // namespace terrain
