#include "render/TextOverlay.h"

#include <stb/stb_easy_font.h>

#include <algorithm>
#include <cstring>

namespace terrain {

Expected<std::unique_ptr<TextOverlay>> TextOverlay::create(const std::filesystem::path& shaderDirectory)
{
    std::unique_ptr<TextOverlay> overlay(new TextOverlay());
    auto program = ShaderProgram::load(shaderDirectory, "text");
    TERRAIN_TRY(program);
    overlay->mProgram = std::move(program.value());
    overlay->mVao = gl::VertexArray::create();
    overlay->mBuffer = gl::Buffer::create();
    glBindVertexArray(overlay->mVao.name());
    glBindBuffer(GL_ARRAY_BUFFER, overlay->mBuffer.name());
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, sizeof(Vertex), reinterpret_cast<const void*>(offsetof(Vertex, x)));
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 4, GL_UNSIGNED_BYTE, GL_TRUE, sizeof(Vertex),
                          reinterpret_cast<const void*>(offsetof(Vertex, rgba)));
    glBindVertexArray(0);
    return overlay;
}

void TextOverlay::draw(const std::vector<std::string>& lines, int width, int height, float scale)
{
    mVertices.clear();
    const float margin = 8.0f, lineHeight = 12.0f;
    // Panel behind the text.
    int widest = 0;
    for (const auto& line : lines) {
        widest = std::max(widest, stb_easy_font_width(const_cast<char*>(line.c_str())));
    }
    auto quad = [&](float x0, float y0, float x1, float y1, const unsigned char* rgba) {
        const Vertex v[4] = {{x0, y0, {rgba[0], rgba[1], rgba[2], rgba[3]}},
                             {x1, y0, {rgba[0], rgba[1], rgba[2], rgba[3]}},
                             {x1, y1, {rgba[0], rgba[1], rgba[2], rgba[3]}},
                             {x0, y1, {rgba[0], rgba[1], rgba[2], rgba[3]}}};
        for (int k : {0, 1, 2, 0, 2, 3}) {
            mVertices.push_back(v[k]);
        }
    };
    const unsigned char panel[4] = {0, 0, 0, 140};
    quad(margin / 2, margin / 2, margin + static_cast<float>(widest) * scale + margin / 2,
         margin + static_cast<float>(lines.size()) * lineHeight * scale + margin / 2, panel);
    // Glyph quads from stb_easy_font: 4 vertices of (x, y, z, rgba) = 16 bytes each.
    for (std::size_t row = 0; row < lines.size(); ++row) {
        mScratch.resize(lines[row].size() * 270 + 64);
        unsigned char white[4] = {255, 255, 255, 255};
        int quads = stb_easy_font_print(0, 0, const_cast<char*>(lines[row].c_str()), white, mScratch.data(),
                                        static_cast<int>(mScratch.size()));
        for (int q = 0; q < quads; ++q) {
            float corners[4][2];
            for (int k = 0; k < 4; ++k) {
                std::memcpy(corners[k], mScratch.data() + (q * 4 + k) * 16, sizeof(float) * 2);
            }
            const float x0 = margin + corners[0][0] * scale,
                        y0 = margin + (corners[0][1] + static_cast<float>(row) * lineHeight) * scale;
            const float x1 = margin + corners[2][0] * scale,
                        y1 = margin + (corners[2][1] + static_cast<float>(row) * lineHeight) * scale;
            quad(x0, y0, x1, y1, white);
        }
    }
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_CULL_FACE);
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    mProgram.use();
    glUniform2f(mProgram.uniform("uViewport"), static_cast<float>(width), static_cast<float>(height));
    glBindVertexArray(mVao.name());
    glBindBuffer(GL_ARRAY_BUFFER, mBuffer.name());
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(mVertices.size() * sizeof(Vertex)), mVertices.data(),
                 GL_STREAM_DRAW);
    glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(mVertices.size()));
    glBindVertexArray(0);
    glDisable(GL_BLEND);
}

}  // namespace terrain
