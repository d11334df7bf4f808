// Per-node visible pixel counts and the frame's depth, read back late (PixelCounter.h).
#include "render/PixelCounter.h"

#include <algorithm>

namespace terrain {

PixelCounter PixelCounter::create()
{
    PixelCounter counter;
    for (Frame& frame : counter.mFrames) {
        frame.buffer = gl::Buffer::create();
        frame.depth = gl::Buffer::create();
    }
    return counter;
}

void PixelCounter::begin(std::uint64_t frame, const Camera& camera)
{
    mCurrent = static_cast<std::size_t>(frame % mFrames.size());
    Frame& f = mFrames[mCurrent];
    if (f.frame != 0) {
        ++mDropped;  // three frames old and never taken
    }
    f.frame = frame;
    f.nodes.clear();
    f.fence.reset();
    f.hasDepth = false;
    f.camera = camera;
}

void PixelCounter::bindCounters()
{
    Frame& f = mFrames[mCurrent];
    const std::size_t count = f.nodes.size();
    // One counter a node, zeroed; the fragment program adds each visible fragment to its node's.
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, f.buffer.name());
    if (f.capacity < count) {
        f.capacity = std::max<std::size_t>(count, 2 * f.capacity);
        glBufferData(GL_SHADER_STORAGE_BUFFER, static_cast<GLsizeiptr>(f.capacity * sizeof(std::uint32_t)), nullptr,
                     GL_DYNAMIC_READ);
    }
    const std::vector<std::uint32_t> zeros(count, 0);
    glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, static_cast<GLsizeiptr>(count * sizeof(std::uint32_t)), zeros.data());
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, f.buffer.name());
}

void PixelCounter::finish()
{
    Frame& f = mFrames[mCurrent];
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, 0);
    // The counters are read by glGetBufferSubData (take) once the fence says the draws are done.
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    // The depth too, into a buffer (no wait here): what the nodes not drawn are tested against.
    const auto pixels = static_cast<std::size_t>(f.camera.viewportWidth) * f.camera.viewportHeight;
    glBindBuffer(GL_PIXEL_PACK_BUFFER, f.depth.name());
    if (f.depthPixels != pixels) {
        glBufferData(GL_PIXEL_PACK_BUFFER, static_cast<GLsizeiptr>(pixels * sizeof(float)), nullptr, GL_STREAM_READ);
        f.depthPixels = pixels;
    }
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glReadPixels(0, 0, f.camera.viewportWidth, f.camera.viewportHeight, GL_DEPTH_COMPONENT, GL_FLOAT, nullptr);
    glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    f.hasDepth = true;
    f.fence = gl::Fence::place();
}

bool PixelCounter::take(PixelCounts& out, std::uint64_t latest, std::uint64_t lag)
{
    Frame* oldest = nullptr;
    for (Frame& f : mFrames) {
        if (f.frame != 0 && f.frame + lag <= latest && (oldest == nullptr || f.frame < oldest->frame)) {
            oldest = &f;
        }
    }
    if (oldest == nullptr) {
        return false;
    }
    out.frame = oldest->frame;
    out.nodes.swap(oldest->nodes);
    oldest->nodes.clear();
    oldest->frame = 0;
    out.pixels.assign(out.nodes.size(), 0);
    out.camera = oldest->camera;
    out.depth.clear();
    if (oldest->fence) {
        // Frames late the GL has long finished: this returns at once, except on a GL that queues more.
        while (!oldest->fence.wait(1'000'000'000)) {
        }
        oldest->fence.reset();
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, oldest->buffer.name());
        glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0,
                           static_cast<GLsizeiptr>(out.pixels.size() * sizeof(std::uint32_t)), out.pixels.data());
        glBindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
        if (oldest->hasDepth) {
            out.depth.resize(static_cast<std::size_t>(out.camera.viewportWidth) * out.camera.viewportHeight);
            glBindBuffer(GL_PIXEL_PACK_BUFFER, oldest->depth.name());
            glGetBufferSubData(GL_PIXEL_PACK_BUFFER, 0, static_cast<GLsizeiptr>(out.depth.size() * sizeof(float)),
                               out.depth.data());
            glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
        }
    }
    return true;
}

}  // namespace terrain
