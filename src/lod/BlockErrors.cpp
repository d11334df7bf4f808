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

namespace terrain {

namespace {

/// The template triangulation's surface at real sample coordinates (x, y), clamped into the node.
double fineAt(std::span<const float> surface, int n, double x, double y)
{
    x = std::clamp(x, 0.0, n - 1.0);
    y = std::clamp(y, 0.0, n - 1.0);
    const int i = std::min(static_cast<int>(x), n - 2), j = std::min(static_cast<int>(y), n - 2);
    const double fx = x - i, fy = y - j;
    auto h = [&](int a, int b) -> double { return surface[static_cast<std::size_t>(j + b) * n + i + a]; };
    return fx >= fy ? (1.0 - fx) * h(0, 0) + (fx - fy) * h(1, 0) + fy * h(1, 1)
                    : (1.0 - fy) * h(0, 0) + (fy - fx) * h(0, 1) + fx * h(1, 1);
}

}  // namespace

double triangleError(std::span<const float> surface, int chunkSize, glm::ivec2 p, glm::ivec2 q, glm::ivec2 r)
{
    const int n = chunkSize;
    auto h = [&](glm::ivec2 v) -> double { return surface[static_cast<std::size_t>(v.y) * n + v.x]; };
    const long area2 = static_cast<long>(q.x - p.x) * (r.y - p.y) - static_cast<long>(q.y - p.y) * (r.x - p.x);
    if (area2 == 0) {
        return 0.0;
    }
    const double hp = h(p), hq = h(q), hr = h(r);
    // The triangle's plane: barycentric weights of (x, y).
    auto plane = [&](double x, double y) {
        const double wq = ((x - p.x) * (r.y - p.y) - (y - p.y) * (r.x - p.x)) / static_cast<double>(area2);
        const double wr = ((q.x - p.x) * (y - p.y) - (q.y - p.y) * (x - p.x)) / static_cast<double>(area2);
        return hp + wq * (hq - hp) + wr * (hr - hp);
    };
    double worst = 0.0;
    // Samples inside (or on) the triangle.
    const int x0 = std::min({p.x, q.x, r.x}), x1 = std::max({p.x, q.x, r.x});
    const int y0 = std::min({p.y, q.y, r.y}), y1 = std::max({p.y, q.y, r.y});
    auto edgeSide = [](glm::ivec2 a, glm::ivec2 b, int x, int y) {
        return static_cast<long>(b.x - a.x) * (y - a.y) - static_cast<long>(b.y - a.y) * (x - a.x);
    };
    const long sign = area2 > 0 ? 1 : -1;
    for (int y = y0; y <= y1; ++y) {
        for (int x = x0; x <= x1; ++x) {
            if (sign * edgeSide(p, q, x, y) >= 0 && sign * edgeSide(q, r, x, y) >= 0 &&
                sign * edgeSide(r, p, x, y) >= 0) {
                worst = std::max(worst, std::abs(h({x, y}) - plane(x, y)));
            }
        }
    }
    // The edges' crossings with the template's lines: x = k, y = k and x - y = k (south-west to north-east).
    for (const auto& edge : {std::pair{p, q}, std::pair{q, r}, std::pair{r, p}}) {
        const glm::ivec2 a = edge.first, b = edge.second;  // not a structured binding: the lambdas capture them
        const double ha = h(a), hb = h(b);
        auto at = [&](double s) {
            const double x = a.x + s * (b.x - a.x), y = a.y + s * (b.y - a.y);
            worst = std::max(worst, std::abs(fineAt(surface, n, x, y) - (ha + s * (hb - ha))));
        };
        auto crossings = [&](int from, int to) {
            if (from == to) {
                return;
            }
            for (int k = std::min(from, to) + 1; k < std::max(from, to); ++k) {
                at(static_cast<double>(k - from) / (to - from));
            }
        };
        crossings(a.x, b.x);
        crossings(a.y, b.y);
        crossings(a.x - a.y, b.x - b.y);
    }
    return worst;
}

float TessellationErrors::snapError(int bx, int by, int side, int t, int e) const
{
    TERRAIN_EXPECTS(t >= 0 && t < e && e <= blocks.levels, "snap levels must satisfy 0 <= t < e <= levels");
    TERRAIN_EXPECTS(side >= 0 && side < 4, "side out of range");
    TERRAIN_EXPECTS(bx >= 0 && bx < blocks.blocksPerSide && by >= 0 && by < blocks.blocksPerSide, "block out of range");
    return snap[static_cast<std::size_t>(((by * blocks.blocksPerSide + bx) * 4 + side) * pairs + e * (e - 1) / 2 + t)];
}

TessellationErrors computeTessellationErrors(std::span<const float> surface, int chunkSize, int blockQuads)
{
    const int n = chunkSize;
    // The surface at morph 0, as the shaders blend (shaders/terrain.vert): odd samples the mean of their
    // even neighbours along x, y or the south-west to north-east diagonal.
    std::vector<float> parent(surface.begin(), surface.end());
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            const int dx = i & 1, dy = j & 1;
            if (dx | dy) {
                parent[static_cast<std::size_t>(j) * n + i] =
                    0.5f * (surface[static_cast<std::size_t>(j - dy) * n + i - dx] +
                            surface[static_cast<std::size_t>(j + dy) * n + i + dx]);
            }
        }
    }
    TessellationErrors out;
    out.blocks = computeBlockErrors(surface, n, blockQuads);
    const BlockErrors atParent = computeBlockErrors(parent, n, blockQuads);
    for (std::size_t k = 0; k < out.blocks.lambda.size(); ++k) {
        out.blocks.lambda[k] = std::max(out.blocks.lambda[k], atParent.lambda[k]);
    }
    const int levels = out.blocks.levels, b = out.blocks.blocksPerSide;
    out.pairs = levels * (levels + 1) / 2;
    out.snap.assign(static_cast<std::size_t>(b) * b * 4 * out.pairs, 0.0f);
    const std::span<const float> surfaces[2] = {surface, parent};
    out.flip.assign(static_cast<std::size_t>(b) * b, 0.0f);
    for (const auto& s : surfaces) {
        for (int j = 0; j + 1 < n; ++j) {
            for (int i = 0; i + 1 < n; ++i) {
                auto h = [&](int a, int c) -> double { return s[static_cast<std::size_t>(j + c) * n + i + a]; };
                // At the quad's centre the two splits differ most: (h00 + h11) / 2 against (h10 + h01) / 2.
                const auto flip = static_cast<float>(0.5 * std::abs(h(0, 0) + h(1, 1) - h(1, 0) - h(0, 1)));
                float& stored = out.flip[static_cast<std::size_t>((j / blockQuads) * b + i / blockQuads)];
                stored = std::max(stored, std::nextafter(flip, INFINITY));
            }
        }
    }
    // Cell (a, c) of the band along `side`, as (a, c) in cells of the block: south row c = 0, east column
    // a = f - 1, north row c = f - 1, west column a = 0.
    auto cellOf = [](int side, int k, int f) -> glm::ivec2 {
        switch (side) {
            case kSouth:
                return {k, 0};
            case kEast:
                return {f - 1, k};
            case kNorth:
                return {k, f - 1};
            default:
                return {0, k};
        }
    };
    for (int by = 0; by < b; ++by) {
        for (int bx = 0; bx < b; ++bx) {
            for (int side = 0; side < 4; ++side) {
                for (int e = 1; e <= levels; ++e) {
                    for (int t = 0; t < e; ++t) {
                        const int f = blockQuads >> t;
                        double worst = 0.0;
                        // The sides crossing this one (they reach its end cells): every level they may take.
                        const int before = side == kSouth || side == kNorth ? kWest : kSouth;
                        const int after = side == kSouth || side == kNorth ? kEast : kNorth;
                        for (int k = 0; k < f; ++k) {
                            const bool end = k == 0 || k == f - 1;
                            for (int adjacent = t; adjacent <= (end ? levels : t); ++adjacent) {
                                int snap[4] = {t, t, t, t};
                                snap[side] = e;
                                if (k == 0) {
                                    snap[before] = adjacent;
                                }
                                if (k == f - 1) {
                                    snap[after] = adjacent;
                                }
                                const glm::ivec2 cell = cellOf(side, k, f);
                                const glm::ivec2 v00 = tessellatedVertex(blockQuads, bx, by, t, cell.x, cell.y, snap);
                                const glm::ivec2 v10 =
                                    tessellatedVertex(blockQuads, bx, by, t, cell.x + 1, cell.y, snap);
                                const glm::ivec2 v11 =
                                    tessellatedVertex(blockQuads, bx, by, t, cell.x + 1, cell.y + 1, snap);
                                const glm::ivec2 v01 =
                                    tessellatedVertex(blockQuads, bx, by, t, cell.x, cell.y + 1, snap);
                                for (const auto& s : surfaces) {
                                    worst = std::max(
                                        {worst, triangleError(s, n, v00, v10, v11), triangleError(s, n, v00, v11, v01),
                                         triangleError(s, n, v00, v10, v01), triangleError(s, n, v10, v11, v01)});
                                }
                            }
                        }
                        float stored = static_cast<float>(worst);
                        if (static_cast<double>(stored) < worst) {
                            stored = std::nextafter(stored, INFINITY);
                        }
                        out.snap[static_cast<std::size_t>(((by * b + bx) * 4 + side) * out.pairs + e * (e - 1) / 2 +
                                                          t)] = stored;
                    }
                }
            }
        }
    }
    return out;
}

}  // namespace terrain
