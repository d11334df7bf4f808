#include "lod/BlockErrors.h"

#include "core/Check.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>

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

/// triangleError over several surfaces at once (the geometry is shared): the largest of their errors.
/// The plane is a gradient from p; the samples inside are tested with exact integer edge functions. The
/// template's lines are crossed at samples (counted by the inside test, edges included) or inside one of
/// its edges, where its surface is the edge's linear interpolation: only those crossings are evaluated.
template <std::size_t S>
double trianglesError(const std::array<const float*, S>& surfaces, int n, glm::ivec2 p, glm::ivec2 q, glm::ivec2 r)
{
    const long area2 = static_cast<long>(q.x - p.x) * (r.y - p.y) - static_cast<long>(q.y - p.y) * (r.x - p.x);
    if (area2 == 0) {
        return 0.0;
    }
    auto at = [n](const float* s, int x, int y) -> double { return s[static_cast<std::size_t>(y) * n + x]; };
    std::array<double, S> hp, gx, gy;  // the plane: hp + gx (x - p.x) + gy (y - p.y)
    for (std::size_t k = 0; k < S; ++k) {
        hp[k] = at(surfaces[k], p.x, p.y);
        const double dq = at(surfaces[k], q.x, q.y) - hp[k], dr = at(surfaces[k], r.x, r.y) - hp[k];
        gx[k] =
            (static_cast<double>(r.y - p.y) * dq - static_cast<double>(q.y - p.y) * dr) / static_cast<double>(area2);
        gy[k] =
            (static_cast<double>(q.x - p.x) * dr - static_cast<double>(r.x - p.x) * dq) / static_cast<double>(area2);
    }
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
                for (std::size_t k = 0; k < S; ++k) {
                    const double plane = hp[k] + gx[k] * (x - p.x) + gy[k] * (y - p.y);
                    worst = std::max(worst, std::abs(at(surfaces[k], x, y) - plane));
                }
            }
        }
    }
    // The edges' crossings with the template's lines x = c, y = c and x - y = c (south-west to north-east)
    // that are not samples: there the template's surface interpolates the ends of one of its edges.
    for (const auto& edge : {std::pair{p, q}, std::pair{q, r}, std::pair{r, p}}) {
        const glm::ivec2 a = edge.first, b = edge.second;
        std::array<double, S> ha, dh;
        for (std::size_t k = 0; k < S; ++k) {
            ha[k] = at(surfaces[k], a.x, a.y);
            dh[k] = at(surfaces[k], b.x, b.y) - ha[k];
        }
        // The crossings with the lines u = c, u = x, y or x - y, strictly between the ends. Along the edge, v
        // (y, or x for u = y) is whole at every `period`-th line: a sample, counted above. Elsewhere the
        // template's edge there runs from `from(c, floor v)` by `step`.
        auto cross = [&](int ua, int ub, int va, int vb, glm::ivec2 step, auto from) {
            const int lo = std::min(ua, ub), span = std::abs(ub - ua);
            if (span < 2) {
                return;
            }
            const int period = span / std::gcd(span, std::abs(vb - va));
            const double inverse = 1.0 / (ub - ua);
            for (int m = 1, phase = 1; m < span; ++m, ++phase) {
                if (phase == period) {
                    phase = 0;
                    continue;
                }
                const int c = lo + m;
                const double s = (c - ua) * inverse;
                const double v = va + s * (vb - va);  // > 0: truncation is floor
                const int whole = static_cast<int>(v);
                const double w = v - whole;
                const glm::ivec2 e = from(c, whole);
                for (std::size_t k = 0; k < S; ++k) {
                    const double onTemplate =
                        (1.0 - w) * at(surfaces[k], e.x, e.y) + w * at(surfaces[k], e.x + step.x, e.y + step.y);
                    worst = std::max(worst, std::abs(onTemplate - (ha[k] + s * dh[k])));
                }
            }
        };
        cross(a.x, b.x, a.y, b.y, {0, 1}, [](int c, int v) { return glm::ivec2{c, v}; });
        cross(a.y, b.y, a.x, b.x, {1, 0}, [](int c, int v) { return glm::ivec2{v, c}; });
        cross(a.x - a.y, b.x - b.y, a.y, b.y, {1, 1}, [](int c, int v) { return glm::ivec2{v + c, v}; });
    }
    return worst;
}

/// The errors of the triangles measured so far for one node, by their corners (in any order): a node's bands
/// meet the same triangle many times (a band's corner cell is also the crossing side's, and snaps to
/// several lattices often land on the same vertices), about half of the measured ones in 8 x 8-quad blocks.
/// Open addressing over a power-of-two table, grown at half full.
class TriangleMemo {
public:
    explicit TriangleMemo(int chunkSize) : mSize(chunkSize)
    {
        TERRAIN_EXPECTS(static_cast<long>(chunkSize) * chunkSize < (1L << 21), "sample indices must fit 21 bits");
        mSlots.resize(1u << 12);
    }

    /// trianglesError of p, q, r over `surfaces`, measured once.
    template <std::size_t S>
    double error(const std::array<const float*, S>& surfaces, glm::ivec2 p, glm::ivec2 q, glm::ivec2 r)
    {
        const long area2 = static_cast<long>(q.x - p.x) * (r.y - p.y) - static_cast<long>(q.y - p.y) * (r.x - p.x);
        if (area2 == 0) {
            return 0.0;
        }
        std::array<std::uint64_t, 3> k = {index(p), index(q), index(r)};
        std::sort(k.begin(), k.end());
        const std::uint64_t key = (k[0] << 42) | (k[1] << 21) | k[2];  // never 0: the corners differ
        Slot& slot = find(key);
        if (slot.key != key) {
            slot = {key, trianglesError(surfaces, mSize, p, q, r)};
            if (++mUsed * 2 > mSlots.size()) {
                grow();
            }
            return find(key).value;
        }
        return slot.value;
    }

private:
    struct Slot {
        std::uint64_t key = 0;  ///< 0: empty
        double value = 0.0;
    };

    std::uint64_t index(glm::ivec2 v) const { return static_cast<std::uint64_t>(v.y) * mSize + v.x; }
    Slot& find(std::uint64_t key)
    {
        const std::size_t mask = mSlots.size() - 1;
        std::size_t i = static_cast<std::size_t>((key * 0x9e3779b97f4a7c15ull) >> 32) & mask;
        while (mSlots[i].key != 0 && mSlots[i].key != key) {
            i = (i + 1) & mask;
        }
        return mSlots[i];
    }
    void grow()
    {
        std::vector<Slot> old(mSlots.size() * 2);
        old.swap(mSlots);
        for (const Slot& slot : old) {
            if (slot.key != 0) {
                find(slot.key) = slot;
            }
        }
    }

    int mSize;
    std::vector<Slot> mSlots;
    std::size_t mUsed = 0;
};

}  // namespace

double triangleError(std::span<const float> surface, int chunkSize, glm::ivec2 p, glm::ivec2 q, glm::ivec2 r)
{
    TERRAIN_EXPECTS(surface.size() == static_cast<std::size_t>(chunkSize) * static_cast<std::size_t>(chunkSize),
                    "the surface must hold N x N heights");
    for (const glm::ivec2 v : {p, q, r}) {
        TERRAIN_EXPECTS(v.x >= 0 && v.y >= 0 && v.x < chunkSize && v.y < chunkSize, "corner outside the node");
    }
    return trianglesError<1>({surface.data()}, chunkSize, p, q, r);
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
    const std::array<const float*, 2> both = {surface.data(), parent.data()};
    TriangleMemo memo(n);
    out.flip.assign(static_cast<std::size_t>(b) * b, 0.0f);
    out.top.assign(static_cast<std::size_t>(b) * b, -std::numeric_limits<float>::infinity());
    for (int by = 0; by < b; ++by) {
        for (int bx = 0; bx < b; ++bx) {
            float& top = out.top[static_cast<std::size_t>(by * b + bx)];
            for (int j = by * blockQuads; j <= (by + 1) * blockQuads; ++j) {
                for (int i = bx * blockQuads; i <= (bx + 1) * blockQuads; ++i) {
                    top = std::max(top, surface[static_cast<std::size_t>(j) * n + i]);
                }
            }
        }
    }
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
                                worst =
                                    std::max({worst, memo.error(both, v00, v10, v11), memo.error(both, v00, v11, v01),
                                              memo.error(both, v00, v10, v01), memo.error(both, v10, v11, v01)});
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
