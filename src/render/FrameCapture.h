// Reading back what was drawn (video mode, GL tests).
#pragma once

#include "heightfield/Image.h"

namespace terrain {

/// The current framebuffer's colour as an RGB image, rows top to bottom (as image files store them).
Image captureFrame(int width, int height);

}  // namespace terrain
