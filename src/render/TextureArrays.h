// Texture arrays of one mip level: the node pools (a layer per slot) and the clipmap's rings (a layer per ring).
#pragma once

#include "render/GlObjects.h"

#include <cstddef>

namespace terrain {

/// How the texels of a texture array are stored and sampled.
struct TextureArrayFormat {
    GLenum internalFormat = GL_RGBA8;
    GLenum format = GL_RGBA;         ///< the upload's format (uncompressed arrays)
    GLenum type = GL_UNSIGNED_BYTE;  ///< the upload's type (uncompressed arrays)
    GLint filter = GL_LINEAR;        ///< min and mag filter
    GLint wrap = GL_REPEAT;          ///< GL_REPEAT (toroidal rings) or GL_CLAMP_TO_EDGE
    /// > 0: a compressed format (S3TC, RGTC) whose layer takes this many bytes; 0: uncompressed.
    std::size_t compressedLayerBytes = 0;
};

/// A texture array of `layers` layers of `size` x `size` texels (compressed: the layer's padded size), one mip
/// level, uninitialised, left bound to GL_TEXTURE_2D_ARRAY.
gl::Texture createTextureArray(const TextureArrayFormat& format, int size, int layers);

}  // namespace terrain
