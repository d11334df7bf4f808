#include "lod/DepthOcclusion.h"

#include "core/Check.h"

#include <algorithm>
#include <cmath>

namespace terrain {

DepthOcclusion::DepthOcclusion(std::span<const float> depth, int width, int height, const Camera& camera)
    : mWidth(width),
      mHeight(height),
      mViewProjection(camera.projection() * camera.viewRotation()),
      mEye(camera.position),
      mNear(camera.nearPlane)
{
    TERRAIN_EXPECTS(width > 0 && height > 0 && depth.size() == static_cast<std::size_t>(width) * height,
                    "one depth a pixel");
    mTilesX = (width + kTile - 1) / kTile;
    mTilesY = (height + kTile - 1) / kTile;
    mTileMax.assign(static_cast<std::size_t>(mTilesX) * mTilesY, 0.0f);
    for (int y = 0; y < height; ++y) {
        const float* row = depth.data() + static_cast<std::size_t>(y) * width;
        float* tiles = mTileMax.data() + static_cast<std::size_t>(y / kTile) * mTilesX;
        for (int x = 0; x < width; ++x) {
            float& t = tiles[x / kTile];
            t = std::max(t, row[x]);
        }
    }
}

bool DepthOcclusion::occluded(const Aabb& box) const
{
    double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300, nearest = 1e300;
    for (int c = 0; c < 8; ++c) {
        const glm::dvec3 corner{(c & 1) ? box.hi.x : box.lo.x, (c & 2) ? box.hi.y : box.lo.y,
                                (c & 4) ? box.hi.z : box.lo.z};
        const glm::dvec4 clip = mViewProjection * glm::dvec4(corner - mEye, 1.0);
        if (!(clip.w > mNear)) {
            return false;  // at or behind the near plane: the box reaches the camera
        }
        const double px = (clip.x / clip.w * 0.5 + 0.5) * mWidth;
        const double py = (clip.y / clip.w * 0.5 + 0.5) * mHeight;
        x0 = std::min(x0, px);
        x1 = std::max(x1, px);
        y0 = std::min(y0, py);
        y1 = std::max(y1, py);
        nearest = std::min(nearest, clip.z / clip.w * 0.5 + 0.5);
    }
    // The pixels the box may cover, a pixel wider each side (rasterisation covers pixel centres); all of them
    // must lie in the image, or part of the box was out of that frame's view.
    const int px0 = static_cast<int>(std::floor(x0)) - 1, px1 = static_cast<int>(std::ceil(x1)) + 1;
    const int py0 = static_cast<int>(std::floor(y0)) - 1, py1 = static_cast<int>(std::ceil(y1)) + 1;
    if (px0 < 0 || py0 < 0 || px1 >= mWidth || py1 >= mHeight) {
        return false;
    }
    // Window depth grows with eye depth, which is linear over the box: the nearest corner is its nearest point.
    for (int ty = py0 / kTile; ty <= py1 / kTile; ++ty) {
        const float* tiles = mTileMax.data() + static_cast<std::size_t>(ty) * mTilesX;
        for (int tx = px0 / kTile; tx <= px1 / kTile; ++tx) {
            if (!(static_cast<double>(tiles[tx]) < nearest)) {
                return false;
            }
        }
    }
    return true;
}

}  // namespace terrain
