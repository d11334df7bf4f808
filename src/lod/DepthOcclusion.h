// Whether boxes lay hidden behind what a frame drew, from that frame's depth buffer (issue 16, visibility_lod):
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
    DepthOcclusion(std::span<const float> depth, int width, int height, const Camera& camera);

    /// Whether all of `box` (world metres) lay behind the frame's surface: its corners in front of the
    /// camera's near plane, their projection inside the image, and nearer no point of the box than the
    /// farthest depth drawn over the rectangle it covers. False whenever that cannot be told (conservative).
    bool occluded(const Aabb& box) const;

    /// Pixels a side of the tiles whose farthest depth the test reads.
    static constexpr int kTile = 8;

private:
    int mWidth = 0, mHeight = 0;
    int mTilesX = 0, mTilesY = 0;
    std::vector<float> mTileMax;      ///< per tile, the farthest depth drawn in it
    glm::dmat4 mViewProjection{1.0};  ///< camera-relative world -> clip
    glm::dvec3 mEye{0.0};
    double mNear = 1.0;
};

}  // namespace terrain
