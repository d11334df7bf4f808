#include "lod/DepthOcclusion.h"

#include "core/Check.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace terrain {

DepthOcclusion::DepthOcclusion(std::span<const float> depth, int width, int height, const Camera& camera,
                               int marginPixels)
    : mWidth(width),
      mHeight(height),
      mViewProjection(camera.projection() * camera.viewRotation()),
      mEye(camera.position),
      mNear(camera.nearPlane),
      mMargin(marginPixels)
{
    TERRAIN_EXPECTS(marginPixels >= 0, "the margin must be >= 0 pixels");
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

bool DepthOcclusion::occluded(const Aabb& unGrown, double growMetres) const
{
    TERRAIN_EXPECTS(growMetres >= 0.0, "a box grows by >= 0 metres");
    const Aabb box{unGrown.lo - glm::dvec3(growMetres), unGrown.hi + glm::dvec3(growMetres)};
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
    // The pixels the box may cover, a pixel wider each side (rasterisation covers pixel centres), within the
    // image: what lies outside it was out of that frame's view, where the frustum culls it (and where the view
    // turns to it the counts and this test see it again a few frames later; the reveal morphs it in).
    const int m = 1 + mMargin;
    const int px0 = std::max(0, static_cast<int>(std::floor(x0)) - m);
    const int px1 = std::min(mWidth - 1, static_cast<int>(std::ceil(x1)) + m);
    const int py0 = std::max(0, static_cast<int>(std::floor(y0)) - m);
    const int py1 = std::min(mHeight - 1, static_cast<int>(std::ceil(y1)) + m);
    if (px0 > px1 || py0 > py1) {
        return false;  // wholly out of view: not a question of occlusion
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

DepthSurface::DepthSurface(std::vector<float> depth, int width, int height, const Camera& camera)
    : mDepth(std::move(depth)),
      mWidth(width),
      mHeight(height),
      mViewProjection(camera.projection() * camera.viewRotation()),
      mEye(camera.position),
      mNear(camera.nearPlane),
      mFar(camera.farPlane)
{
    TERRAIN_EXPECTS(width > 0 && height > 0 && mDepth.size() == static_cast<std::size_t>(width) * height,
                    "one depth a pixel");
}

bool DepthSurface::shows(const glm::dvec3& point, double slack) const
{
    TERRAIN_EXPECTS(slack >= 0.0, "the slack must be >= 0");
    const glm::dvec4 clip = mViewProjection * glm::dvec4(point - mEye, 1.0);
    if (!(clip.w > mNear)) {
        return false;
    }
    const double px = (clip.x / clip.w * 0.5 + 0.5) * mWidth;
    const double py = (clip.y / clip.w * 0.5 + 0.5) * mHeight;
    if (!(px >= 0.0 && py >= 0.0 && px < mWidth && py < mHeight)) {
        return false;
    }
    const int x = static_cast<int>(px), y = static_cast<int>(py);
    float farthest = 0.0f;
    for (int j = std::max(0, y - 1); j <= std::min(mHeight - 1, y + 1); ++j) {
        for (int i = std::max(0, x - 1); i <= std::min(mWidth - 1, x + 1); ++i) {
            farthest = std::max(farthest, mDepth[static_cast<std::size_t>(j) * mWidth + i]);
        }
    }
    if (farthest >= 1.0f) {
        return true;  // nothing drawn next to it: a silhouette against the sky
    }
    // Window depth back to eye distance (OpenGL's perspective depth, range [0, 1]).
    const double ndc = 2.0 * farthest - 1.0;
    const double eye = 2.0 * mFar * mNear / (mFar + mNear - ndc * (mFar - mNear));
    return clip.w <= eye * (1.0 + slack);
}

}  // namespace terrain
