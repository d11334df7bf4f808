// The on-screen statistics (config draw_user_interface): lines of text on a translucent panel, drawn
// with stb_easy_font's quads (public domain; Debian libstb-dev) — no font files to ship.
#pragma once

#include "core/Expected.h"
#include "render/GlObjects.h"
#include "render/ShaderProgram.h"

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace terrain {

class TextOverlay {
public:
    static Expected<std::unique_ptr<TextOverlay>> create(const std::filesystem::path& shaderDirectory);

    /// Draws `lines` at the top-left corner of a `width` x `height` viewport, `scale` pixels per font unit.
    void draw(const std::vector<std::string>& lines, int width, int height, float scale = 2.0f);

private:
    struct Vertex {
        float x, y;
        unsigned char rgba[4];
    };
    ShaderProgram mProgram;
    gl::VertexArray mVao;
    gl::Buffer mBuffer;
    std::vector<Vertex> mVertices;
    std::vector<char> mScratch;
};

}  // namespace terrain
