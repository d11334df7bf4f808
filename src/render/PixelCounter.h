// The visible pixels of each node a frame draws (visibility_lod; Özak & Demir, seed 001, method 2): a counter
// per drawn node in a shader storage buffer (binding 0) that the fragment program adds each fragment passing the
// depth test to, and the frame's depth read into a buffer, both taken some frames later when the GL has long
// finished them, so that reading them does not wait. Three frames' buffers in turn.
#pragma once

#include "core/Camera.h"
#include "lod/NodeVisibility.h"
#include "quadtree/NodeId.h"
#include "render/GlObjects.h"

#include <array>
#include <cstdint>
#include <vector>

namespace terrain {

class PixelCounter {
public:
    /// The buffers. Needs a current GL context with shader storage buffers.
    static PixelCounter create();

    /// Starts frame `frame` (increasing from 1), drawn with `camera`: its counts replace those of the frame three
    /// before, which are dropped if they were never taken.
    void begin(std::uint64_t frame, const Camera& camera);
    /// The next counter is node `id`'s (in drawing order).
    void add(const NodeId& id) { mFrames[mCurrent].nodes.push_back(id); }
    /// Zeroes the frame's counters and binds them as shader storage buffer 0, before its draws.
    void bindCounters();
    /// After the frame's draws: unbinds the counters, reads the depth buffer (the camera's viewport) into a
    /// buffer and places a fence.
    void finish();
    /// The counts of the oldest frame not yet taken drawn at least `lag` frames before `latest`, into `out`;
    /// false when there is none.
    bool take(PixelCounts& out, std::uint64_t latest, std::uint64_t lag);
    /// Frames whose counts were dropped untaken.
    std::uint64_t dropped() const { return mDropped; }

private:
    struct Frame {
        gl::Buffer buffer;
        std::size_t capacity = 0;  ///< nodes the buffer holds
        gl::Fence fence;           ///< after the frame's draws; none when nothing was drawn
        std::uint64_t frame = 0;   ///< 0: nothing waiting to be taken
        std::vector<NodeId> nodes;
        gl::Buffer depth;             ///< pixel pack buffer the depth is read into
        std::size_t depthPixels = 0;  ///< its size
        bool hasDepth = false;        ///< this frame's depth was read
        Camera camera;
    };
    std::array<Frame, 3> mFrames;
    std::size_t mCurrent = 0;
    std::uint64_t mDropped = 0;
};

}  // namespace terrain
