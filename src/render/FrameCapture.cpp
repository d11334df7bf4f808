#include "render/FrameCapture.h"

#include <epoxy/gl.h>

#include <algorithm>

namespace terrain {

Image captureFrame(int width, int height)
{
    Image image{width, height, 3, std::vector<std::uint8_t>(static_cast<std::size_t>(width) * height * 3)};
    std::vector<std::uint8_t> bottomUp(image.pixels.size());
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    // The window's back buffer, or the framebuffer object a headless context draws into.
    GLint framebuffer = 0;
    glGetIntegerv(GL_READ_FRAMEBUFFER_BINDING, &framebuffer);
    glReadBuffer(framebuffer == 0 ? GL_BACK : GL_COLOR_ATTACHMENT0);
    glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, bottomUp.data());
    const std::size_t row = static_cast<std::size_t>(width) * 3;
    for (int y = 0; y < height; ++y) {
        std::copy_n(&bottomUp[static_cast<std::size_t>(height - 1 - y) * row], row, image.pixel(0, y));
    }
    return image;
}

}  // namespace terrain
