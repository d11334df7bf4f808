#include "lod/BlockErrors.h"

#include "core/Check.h"

#include <algorithm>
#include <bit>
#include <cmath>

namespace terrain {

float BlockErrors::at(int bx, int by, int d) const
{
    TERRAIN_EXPECTS(bx >= 0 && bx < blocksPerSide && by >= 0 && by < blocksPerSide, "block out of range");
    TERRAIN_EXPECTS(d >= 1 && d <= levels, "simplification level out of range");
    return lambda[static_cast<std::size_t>((by * blocksPerSide + bx) * levels + d - 1)];
}

BlockErrors computeBlockErrors(std::span<const float> surface, int chunkSize, int blockQuads)
{
    const int n = chunkSize;
    TERRAIN_EXPECTS(n >= 3, "a node has at least 3 x 3 samples");
    TERRAIN_EXPECTS(surface.size() == static_cast<std::size_t>(n) * static_cast<std::size_t>(n),
                    "the surface must hold N x N heights");
    TERRAIN_EXPECTS(
        blockQuads >= 2 && std::has_single_bit(static_cast<unsigned>(blockQuads)) && (n - 1) % blockQuads == 0,
        "blocks must be a power of two >= 2 quads a side that divides N - 1");
    BlockErrors out;
    out.blockQuads = blockQuads;
    out.blocksPerSide = (n - 1) / blockQuads;
    out.levels = std::countr_zero(static_cast<unsigned>(blockQuads));
    out.lambda.assign(static_cast<std::size_t>(out.blocksPerSide * out.blocksPerSide * out.levels), 0.0f);
    auto h = [&](int i, int j) -> double { return surface[static_cast<std::size_t>(j) * n + i]; };

    for (int by = 0; by < out.blocksPerSide; ++by) {
        for (int bx = 0; bx < out.blocksPerSide; ++bx) {
            const int i0 = bx * blockQuads, j0 = by * blockQuads;
            double previous = 0.0;
            for (int d = 1; d <= out.levels; ++d) {
                const int step = 1 << d;
                double worst = 0.0;
                // Each coarse quad of the block, against the fine surface at its samples and quad centres,
                // in half-sample units (a, b): even a and b are samples, odd both are quad centres.
                for (int cj = j0; cj < j0 + blockQuads; cj += step) {
                    for (int ci = i0; ci < i0 + blockQuads; ci += step) {
                        const double h00 = h(ci, cj), h10 = h(ci + step, cj);
                        const double h01 = h(ci, cj + step), h11 = h(ci + step, cj + step);
                        for (int b = 0; b <= 2 * step; ++b) {
                            for (int a = 0; a <= 2 * step; ++a) {
                                if ((a & 1) != (b & 1)) {
                                    continue;  // the middle of a fine edge: both surfaces are linear there
                                }
                                const double fine =
                                    (a & 1) ? 0.5 * (h(ci + a / 2, cj + b / 2) + h(ci + a / 2 + 1, cj + b / 2 + 1))
                                            : h(ci + a / 2, cj + b / 2);
                                const double fx = a / (2.0 * step), fy = b / (2.0 * step);
                                // South-west to north-east split, and north-west to south-east.
                                const double swne = fx >= fy ? (1.0 - fx) * h00 + (fx - fy) * h10 + fy * h11
                                                             : (1.0 - fy) * h00 + (fy - fx) * h01 + fx * h11;
                                const double nwse = fx + fy <= 1.0
                                                        ? h00 + fx * (h10 - h00) + fy * (h01 - h00)
                                                        : h11 + (1.0 - fx) * (h01 - h11) + (1.0 - fy) * (h10 - h11);
                                worst = std::max({worst, std::abs(fine - swne), std::abs(fine - nwse)});
                            }
                        }
                    }
                }
                previous = std::max(previous, worst);
                // Rounded up, so the float never reports less than the double measured.
                float stored = static_cast<float>(previous);
                if (static_cast<double>(stored) < previous) {
                    stored = std::nextafter(stored, INFINITY);
                }
                out.lambda[static_cast<std::size_t>((by * out.blocksPerSide + bx) * out.levels + d - 1)] = stored;
            }
        }
    }
    return out;
}

}  // namespace terrain
