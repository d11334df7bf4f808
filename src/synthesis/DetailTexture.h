// Procedural detail textures for materials (paper 3.4.5: "higher resolution textures would be
// appreciated"): a tileable gray image of a fractal, multiplied over a dynamic node's colour. The shipped
// materials/*_detail.png are made by this (MaterialTest checks they still match it).
#pragma once

#include "heightfield/Image.h"
#include "synthesis/Fractal.h"

namespace terrain {

/// A size x size gray image of the tileable fractal of `params` (the one FractalCache::Fractal tabulates,
/// kCachedFractalTileWavelengths base wavelengths per image): pixel = round(127.5 + 127.5 * value /
/// amplitude), so it tiles without a seam. Preconditions: size > 0, params valid with amplitude > 0.
Image makeDetailTexture(const FractalParams& params, int size);

/// The one-channel image `image` with its histogram made Gaussian of the same mean and standard deviation, the
/// order of its pixels kept: each gray takes the normal quantile of its pixels' mid-rank (the quantiles scaled to
/// the image's mean and deviation over its pixels), rounded and clamped to [0, 255]. What histogram-preserving
/// tiling (shaders/detail.glsl) needs of a texture. A flat image stays flat.
/// Precondition: one channel, at least one pixel.
Image gaussianized(const Image& image);

/// The mean of a one-channel image's pixels, as a fraction of 255.
double meanGray(const Image& image);

}  // namespace terrain
