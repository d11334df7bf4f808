// Geomorph targets (eq. 3.4) and morphing normals of one node, for the template mesh.
#include "gpudata/NodeVertexData.h"

#include "core/Check.h"
#include "quadtree/ChunkGeometry.h"

#include <algorithm>
#include <cmath>

namespace terrain {

namespace {

std::int16_t toSnorm16(double v)
{
    return static_cast<std::int16_t>(std::lround(std::clamp(v, -1.0, 1.0) * 32767.0));
}

}  // namespace

std::vector<NodeVertex> buildNodeVertices(const TemplateMesh& mesh, std::span<const float> window, double spacing,
                                          std::span<const std::uint8_t> materialWeights)
{
    const int n = mesh.chunkSize;
    const int w = windowSize(n);
    TERRAIN_EXPECTS(window.size() == static_cast<std::size_t>(w) * w, "window must be (N + 4)^2 heights");
    TERRAIN_EXPECTS(materialWeights.empty() || materialWeights.size() == static_cast<std::size_t>(n) * n * 4,
                    "material weights must be N x N x 4 bytes");
    auto code = [&](int i, int j) -> double { return window[static_cast<std::size_t>(j + kBorder) * w + i + kBorder]; };
    // Slopes in metres per sample, turned into unit normals (x, y) with the spacing.
    const double scale = 1.0 / spacing;
    auto normal = [&](double gx, double gy, std::int16_t* out) {
        const double x = -gx * scale, y = -gy * scale;
        const double length = std::sqrt(x * x + y * y + 1.0);
        out[0] = toSnorm16(x / length);
        out[1] = toSnorm16(y / length);
    };
    // The parent's unit normal (x, y) at one of its samples: its own central difference, two node samples
    // either side.
    auto parentNormal = [&](int i, int j, double& nx, double& ny) {
        const double x = -(code(i + 2, j) - code(i - 2, j)) * 0.25 * scale;
        const double y = -(code(i, j + 2) - code(i, j - 2)) * 0.25 * scale;
        const double length = std::sqrt(x * x + y * y + 1.0);
        nx = x / length;
        ny = y / length;
    };
    std::vector<NodeVertex> vertices(mesh.vertices.size());
    for (std::size_t k = 0; k < mesh.vertices.size(); ++k) {
        const int i = mesh.vertices[k].i, j = mesh.vertices[k].j;
        NodeVertex& v = vertices[k];
        const double own = code(i, j);
        // The two parent samples the vertex lies between (along x, y or the SW-NE diagonal): the parent's
        // surface and (x, y) of its normal are their means, as the parent's triangles interpolate them.
        const int dx = i & 1, dy = j & 1;
        double parent = own, pnx = 0, pny = 0;
        if (dx || dy) {
            parent = 0.5 * (code(i - dx, j - dy) + code(i + dx, j + dy));
            double ax, ay, bx, by;
            parentNormal(i - dx, j - dy, ax, ay);
            parentNormal(i + dx, j + dy, bx, by);
            pnx = 0.5 * (ax + bx);
            pny = 0.5 * (ay + by);
        } else {
            parentNormal(i, j, pnx, pny);
        }
        v.own = static_cast<float>(own);
        v.parent = static_cast<float>(parent);
        if (!materialWeights.empty()) {
            const std::uint8_t* weights = materialWeights.data() + (static_cast<std::size_t>(j) * n + i) * 4;
            std::copy(weights, weights + 4, v.materialWeights);
        }
        normal((code(i + 1, j) - code(i - 1, j)) * 0.5, (code(i, j + 1) - code(i, j - 1)) * 0.5, v.ownNormal);
        v.parentNormal[0] = toSnorm16(pnx);
        v.parentNormal[1] = toSnorm16(pny);
    }
    return vertices;
}

}  // namespace terrain
