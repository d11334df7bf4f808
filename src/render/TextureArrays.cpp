// Texture arrays of one mip level (TextureArrays.h).
#include "render/TextureArrays.h"

namespace terrain {

gl::Texture createTextureArray(const TextureArrayFormat& f, int size, int layers)
{
    gl::Texture texture = gl::Texture::create();
    glBindTexture(GL_TEXTURE_2D_ARRAY, texture.name());
    if (f.compressedLayerBytes > 0) {
        glCompressedTexImage3D(GL_TEXTURE_2D_ARRAY, 0, f.internalFormat, size, size, layers, 0,
                               static_cast<GLsizei>(f.compressedLayerBytes * static_cast<std::size_t>(layers)),
                               nullptr);
    } else {
        glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, static_cast<GLint>(f.internalFormat), size, size, layers, 0, f.format,
                     f.type, nullptr);
    }
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAX_LEVEL, 0);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, f.filter);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, f.filter);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_S, f.wrap);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_WRAP_T, f.wrap);
    return texture;
}

}  // namespace terrain
