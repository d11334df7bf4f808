// Whether boxes lay hidden behind what a frame drew, from that frame's depth buffer (visibility_lod):
// the test for nodes that have no pixel counts of their own yet (new in view, just split), so that terrain
// appearing behind a ridge is not refined, loaded or synthesized for the frames until its counts say so
// (Özak & Demir, seed 001, test the previous frame's results; the box against its depth is the conservative
// form for what it did not draw). Pure: the depth comes from TerrainRenderer's read-back.
#pragma once

#include "core/Aabb.h"
#include "core/Camera.h"

#include <glm/mat4x4.hpp>

#include <span>
#include <vector>

namespace terrain {

class DepthOcclusion {
public:
    /// `depth`: `width` x `height` window-space depths in [0, 1] (1 where nothing was drawn), row 0 at the
    /// bottom, as glReadPixels gives them, of a frame drawn with `camera` (its viewport the same size).
    /// `marginPixels` (>= 0) widens every box's rectangle by that much each side: the frames drawn since that
    /// depth moved the image, and what the box would show must lie behind the depth that far around it.
    DepthOcclusion(std::span<const float> depth, int width, int height, const Camera& camera, int marginPixels = 0);

    /// Whether all of `box` (world metres) that was in the frame's view lay behind its surface: its corners in
    /// front of the camera's near plane, and no point of the box nearer than the farthest depth drawn over the
    /// part of the image its projection covers (outside the image nothing was drawn to hide or show). False
    /// whenever that cannot be told (a corner at or behind the near plane, the box wholly out of the image).
    /// With `growMetres` > 0 the box is first grown by that much on every side: the distance the viewer has
    /// moved since the frame, so that what the box holds stays hidden from anywhere along the way (as far
    /// as moving the box the other way tells).
    bool occluded(const Aabb& box, double growMetres = 0.0) const;
    /// Where the frame's camera was.
    const glm::dvec3& eye() const { return mEye; }

    /// Pixels a side of the tiles whose farthest depth the test reads.
    static constexpr int kTile = 8;

private:
    int mWidth = 0, mHeight = 0;
    int mTilesX = 0, mTilesY = 0;
    std::vector<float> mTileMax;      ///< per tile, the farthest depth drawn in it
    glm::dmat4 mViewProjection{1.0};  ///< camera-relative world -> clip
    glm::dvec3 mEye{0.0};
    double mNear = 1.0;
    int mMargin = 0;
};

/// A frame's own depth, for measuring what it shows (tengine measure_error_every): whether a point lies on the
/// surface the frame drew, or in front of it, rather than behind it.
class DepthSurface {
public:
    /// `depth` as for DepthOcclusion, of a frame drawn with `camera`.
    DepthSurface(std::vector<float> depth, int width, int height, const Camera& camera);

    /// Whether the point (world metres) shows: in front of the near plane, inside the image, and at most
    /// `slack` (a fraction, >= 0) farther than the farthest depth drawn in the 3 x 3 pixels around its own
    /// (rasterisation samples pixel centres; a steep or grazing surface changes depth within a pixel). Points
    /// outside the image do not show.
    bool shows(const glm::dvec3& point, double slack = 0.02) const;

private:
    std::vector<float> mDepth;
    int mWidth = 0, mHeight = 0;
    glm::dmat4 mViewProjection{1.0};
    glm::dvec3 mEye{0.0};
    double mNear = 1.0, mFar = 2.0;
};

}  // namespace terrain
