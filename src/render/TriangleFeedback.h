// A test hook of the tessellation mode: the camera-relative corners of every triangle the tessellator makes,
// read back by transform feedback (the programs' varying vRelative), three a triangle, in drawing order.
#pragma once

#include "render/GlObjects.h"

#include <glm/vec3.hpp>

#include <cstdint>
#include <vector>

namespace terrain {

class TriangleFeedback {
public:
    /// Room for `triangles` triangles this frame (the draws' own count: BlockLevels::triangles()).
    void begin(std::uint64_t triangles);
    /// Wraps one draw call (feedback cannot span a program change): its triangles go after the previous draw's.
    /// Counts the primitives the GL says it generated into `generated`.
    void beginDraw();
    void endDraw(std::uint64_t& generated);
    /// The corners captured this frame, into `out` (waits for the GL).
    void read(std::vector<glm::vec3>& out);

private:
    gl::Buffer mBuffer;
    std::uint64_t mCapacity = 0;          ///< triangles this frame
    std::uint64_t mCaptured = 0;          ///< triangles written so far
    GLuint mWritten = 0, mGenerated = 0;  ///< the current draw's queries
};

}  // namespace terrain
