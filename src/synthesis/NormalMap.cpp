// Per-node normal maps (paper 4.2.4, Appendix A dynamic_texture_size).
#include "synthesis/NormalMap.h"

#include "core/Check.h"

#include <algorithm>
#include <cmath>

namespace terrain {

int normalMapCells(int textureSize)
{
    TERRAIN_EXPECTS(isPowerOfTwo(textureSize) || isPowerOfTwoPlusOne(textureSize),
                    "dynamic_texture_size must be 2^k or 2^k + 1");
    TERRAIN_EXPECTS(textureSize >= 2, "a normal map has at least 2 texels a side");
    return isPowerOfTwoPlusOne(textureSize) ? textureSize - 1 : textureSize;
}

int normalMapDepth(int cells, int chunkSize)
{
    TERRAIN_EXPECTS(isValidChunkSize(chunkSize), "chunk size must be 2^k + 1");
    int depth = 0;
    while (depth < kMaxNormalMapDepth && ((chunkSize - 1) << depth) < cells) {
        ++depth;
    }
    return depth;
}

std::vector<float> surfaceBelow(const DetailSynthesizer& synthesizer, const std::array<DualHeightMap, 4>& children,
                                const WindowPlacement& where, int depth)
{
    TERRAIN_EXPECTS(depth >= 1 && depth <= kMaxNormalMapDepth, "depth must be in [1, kMaxNormalMapDepth]");
    const int n = synthesizer.chunkSize();
    // Each child's surface below, one level less deep, fills its quarter of the window; where two children's
    // windows overlap (the shared edge and the borders), the sample is taken from the child it lies inside.
    const int half = (n - 1) << (depth - 1);  // cells of a child's part
    const int w = 2 * half + 1 + 2 * kBorder;
    const int wc = half + 1 + 2 * kBorder;
    std::vector<float> out(static_cast<std::size_t>(w) * w);
    for (int q = 0; q < 4; ++q) {
        const int qx = q & 1, qy = q >> 1;
        const std::vector<float> sub =
            surfaceBelow(synthesizer, children[static_cast<std::size_t>(q)], childPlacement(where, q, n), depth - 1);
        const int fx0 = qx == 0 ? 0 : half + kBorder + 1, fx1 = qx == 0 ? half + kBorder : w - 1;
        const int fy0 = qy == 0 ? 0 : half + kBorder + 1, fy1 = qy == 0 ? half + kBorder : w - 1;
        for (int fj = fy0; fj <= fy1; ++fj) {
            const int cj = fj - qy * half;
            for (int fi = fx0; fi <= fx1; ++fi) {
                out[static_cast<std::size_t>(fj) * w + fi] = sub[static_cast<std::size_t>(cj) * wc + fi - qx * half];
            }
        }
    }
    return out;
}

std::vector<float> surfaceBelow(const DetailSynthesizer& synthesizer, const DualHeightMap& node,
                                const WindowPlacement& where, int depth)
{
    TERRAIN_EXPECTS(depth >= 0 && depth <= kMaxNormalMapDepth, "depth must be in [0, kMaxNormalMapDepth]");
    TERRAIN_EXPECTS(node.size == windowSize(synthesizer.chunkSize()),
                    "the node's window does not match the synthesizer's chunk size");
    if (depth == 0) {
        std::vector<float> own(node.base.size());
        node.surface(own);
        return own;
    }
    return surfaceBelow(synthesizer, synthesizer.synthesizeChildren(node, where, ShownWeights::Skip), where, depth);
}

namespace {

std::int8_t snorm8(double v)
{
    return static_cast<std::int8_t>(std::lround(std::clamp(v, -1.0, 1.0) * 127.0));
}

void putNormal(double gx, double gy, std::int8_t* out)
{
    const double inverse = 1.0 / std::sqrt(gx * gx + gy * gy + 1.0);
    out[0] = snorm8(-gx * inverse);
    out[1] = snorm8(-gy * inverse);
}

}  // namespace

std::vector<std::int8_t> normalMapOf(std::span<const float> window, int cells, double spacing, int texels)
{
    const int w = cells + 1 + 2 * kBorder;
    TERRAIN_EXPECTS(cells >= 1 && window.size() == static_cast<std::size_t>(w) * w,
                    "the window holds (cells + 1 + 2 kBorder)^2 samples");
    TERRAIN_EXPECTS(texels >= 2 && spacing > 0.0, "at least 2 texels a side and a spacing > 0");
    const int tc = texels - 1;
    auto h = [&](int i, int j) { return static_cast<double>(window[static_cast<std::size_t>(j) * w + i]); };
    std::vector<std::int8_t> out(static_cast<std::size_t>(texels) * texels * 2);
    if (cells % tc == 0) {
        // Every texel on a sample: the central difference over the texel's own width, as far as the border
        // reaches (a coarser map averages the finer slopes instead of picking one sample's).
        const int k = cells / tc;
        const int d = std::min(k, kBorder);
        const double scale = 1.0 / (2.0 * d * spacing);
        for (int tj = 0; tj < texels; ++tj) {
            const int j = kBorder + tj * k;
            for (int ti = 0; ti < texels; ++ti) {
                const int i = kBorder + ti * k;
                putNormal((h(i + d, j) - h(i - d, j)) * scale, (h(i, j + d) - h(i, j - d)) * scale,
                          out.data() + (static_cast<std::size_t>(tj) * texels + ti) * 2);
            }
        }
        return out;
    }
    TERRAIN_EXPECTS(tc % cells == 0, "texel cells and sample cells must be powers of two");
    // More texels than samples: the samples' gradients (central differences) interpolated bilinearly.
    const int m = cells + 1;
    std::vector<double> gx(static_cast<std::size_t>(m) * m), gy(gx.size());
    const double scale = 1.0 / (2.0 * spacing);
    for (int j = 0; j < m; ++j) {
        for (int i = 0; i < m; ++i) {
            const int wi = i + kBorder, wj = j + kBorder;
            gx[static_cast<std::size_t>(j) * m + i] = (h(wi + 1, wj) - h(wi - 1, wj)) * scale;
            gy[static_cast<std::size_t>(j) * m + i] = (h(wi, wj + 1) - h(wi, wj - 1)) * scale;
        }
    }
    const int per = tc / cells;  // texels per sample cell
    for (int tj = 0; tj < texels; ++tj) {
        const int j0 = std::min(tj / per, cells - 1);
        const double fy = static_cast<double>(tj - j0 * per) / per;
        for (int ti = 0; ti < texels; ++ti) {
            const int i0 = std::min(ti / per, cells - 1);
            const double fx = static_cast<double>(ti - i0 * per) / per;
            auto lerp2 = [&](const std::vector<double>& g) {
                auto at = [&](int i, int j) { return g[static_cast<std::size_t>(j) * m + i]; };
                const double south = at(i0, j0) + fx * (at(i0 + 1, j0) - at(i0, j0));
                const double north = at(i0, j0 + 1) + fx * (at(i0 + 1, j0 + 1) - at(i0, j0 + 1));
                return south + fy * (north - south);
            };
            putNormal(lerp2(gx), lerp2(gy), out.data() + (static_cast<std::size_t>(tj) * texels + ti) * 2);
        }
    }
    return out;
}

std::vector<std::int8_t> makeNormalMap(const DetailSynthesizer& synthesizer, const DualHeightMap& node,
                                       const WindowPlacement& where, int textureSize)
{
    const int cells = normalMapCells(textureSize);
    const int n = synthesizer.chunkSize();
    const int depth = normalMapDepth(cells, n);
    const std::vector<float> below = surfaceBelow(synthesizer, node, where, depth);
    return normalMapOf(below, (n - 1) << depth, where.spacing / static_cast<double>(1 << depth), cells + 1);
}

std::vector<std::int8_t> makeNormalMap(const DetailSynthesizer& synthesizer, const DualHeightMap& node,
                                       const std::array<DualHeightMap, 4>& children, const WindowPlacement& where,
                                       int textureSize)
{
    const int cells = normalMapCells(textureSize);
    const int n = synthesizer.chunkSize();
    const int depth = normalMapDepth(cells, n);
    const std::vector<float> below =
        depth == 0 ? surfaceBelow(synthesizer, node, where, 0) : surfaceBelow(synthesizer, children, where, depth);
    return normalMapOf(below, (n - 1) << depth, where.spacing / static_cast<double>(1 << depth), cells + 1);
}

}  // namespace terrain
