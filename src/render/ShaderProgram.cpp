#include "render/ShaderProgram.h"

#include "render/ShaderContract.h"

#include <algorithm>

namespace terrain {

namespace {

/// Inserts the C++/GLSL contract's definitions (render/ShaderContract.h) and `defines` after the #version line
/// (which must come first in GLSL).
std::string withDefines(const std::string& source, const std::vector<std::string>& defines)
{
    std::string block;
    for (const auto& d : contract::shaderContractDefines()) {
        block += "#define " + d + "\n";
    }
    for (const auto& d : defines) {
        block += "#define " + d + "\n";
    }
    auto version = source.find("#version");
    if (version == std::string::npos) {
        return block + source;
    }
    auto lineEnd = source.find('\n', version);
    lineEnd = lineEnd == std::string::npos ? source.size() : lineEnd + 1;
    // Keep the driver's line numbers matching the file: reset with #line after the defines.
    std::size_t versionLine = 1 + static_cast<std::size_t>(std::count(
                                      source.begin(), source.begin() + static_cast<std::ptrdiff_t>(lineEnd), '\n'));
    return source.substr(0, lineEnd) + block + "#line " + std::to_string(versionLine) + "\n" + source.substr(lineEnd);
}

Expected<GLuint> compile(GLenum type, const std::string& name, const std::string& source)
{
    GLuint shader = glCreateShader(type);
    const char* text = source.c_str();
    glShaderSource(shader, 1, &text, nullptr);
    glCompileShader(shader);
    GLint ok = GL_FALSE;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (ok != GL_TRUE) {
        GLint length = 0;
        glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
        std::string log(static_cast<std::size_t>(std::max(length, 1)), '\0');
        glGetShaderInfoLog(shader, length, nullptr, log.data());
        glDeleteShader(shader);
        while (!log.empty() && (log.back() == '\0' || log.back() == '\n')) {
            log.pop_back();
        }
        return makeError(name, ": shader does not compile:\n", log);
    }
    return shader;
}

}  // namespace

Expected<ShaderProgram> ShaderProgram::link(const std::string& name, const std::vector<Stage>& stages,
                                            const std::vector<std::string>& defines,
                                            const std::vector<std::string>& feedback)
{
    std::vector<GLuint> shaders;
    auto release = [&] {
        for (GLuint shader : shaders) {
            glDeleteShader(shader);
        }
    };
    for (const Stage& stage : stages) {
        auto shader = compile(stage.type, stage.file, withDefines(stage.source, defines));
        if (!shader.ok()) {
            release();
            return shader.error();
        }
        shaders.push_back(*shader);
    }
    ShaderProgram program;
    program.mProgram = gl::Program::create();
    for (GLuint shader : shaders) {
        glAttachShader(program.name(), shader);
    }
    if (!feedback.empty()) {
        std::vector<const char*> names;
        for (const auto& f : feedback) {
            names.push_back(f.c_str());
        }
        glTransformFeedbackVaryings(program.name(), static_cast<GLsizei>(names.size()), names.data(),
                                    GL_INTERLEAVED_ATTRIBS);
    }
    glLinkProgram(program.name());
    release();
    GLint ok = GL_FALSE;
    glGetProgramiv(program.name(), GL_LINK_STATUS, &ok);
    if (ok != GL_TRUE) {
        GLint length = 0;
        glGetProgramiv(program.name(), GL_INFO_LOG_LENGTH, &length);
        std::string log(static_cast<std::size_t>(std::max(length, 1)), '\0');
        glGetProgramInfoLog(program.name(), length, nullptr, log.data());
        return makeError(name, ": shader program does not link:\n", log);
    }
    return program;
}

Expected<ShaderProgram> ShaderProgram::fromSource(const std::string& name, const std::string& vertex,
                                                  const std::string& fragment, const std::vector<std::string>& defines)
{
    return link(name, {{GL_VERTEX_SHADER, name + ".vert", vertex}, {GL_FRAGMENT_SHADER, name + ".frag", fragment}},
                defines, {});
}

Expected<ShaderProgram> ShaderProgram::load(const std::filesystem::path& directory, const std::string& name,
                                            const std::vector<std::string>& defines,
                                            const std::vector<std::string>& feedback)
{
    auto vertex = readShaderFile(directory / (name + ".vert"));
    TERRAIN_TRY(vertex);
    auto fragment = readShaderFile(directory / (name + ".frag"));
    TERRAIN_TRY(fragment);
    const std::string path = (directory / name).string();
    return link(path, {{GL_VERTEX_SHADER, path + ".vert", *vertex}, {GL_FRAGMENT_SHADER, path + ".frag", *fragment}},
                defines, feedback);
}

Expected<ShaderProgram> ShaderProgram::loadTessellation(const std::filesystem::path& directory,
                                                        const std::string& vertex, const std::string& name,
                                                        const std::vector<std::string>& defines,
                                                        const std::vector<std::string>& feedback)
{
    std::vector<Stage> stages;
    for (auto [type, file] :
         {std::pair{GL_VERTEX_SHADER, vertex + ".vert"}, std::pair{GL_TESS_CONTROL_SHADER, name + ".tesc"},
          std::pair{GL_TESS_EVALUATION_SHADER, name + ".tese"}, std::pair{GL_FRAGMENT_SHADER, name + ".frag"}}) {
        auto text = readShaderFile(directory / file);
        TERRAIN_TRY(text);
        stages.push_back({static_cast<GLenum>(type), (directory / file).string(), std::move(text).value()});
    }
    return link((directory / name).string(), stages, defines, feedback);
}

GLint ShaderProgram::uniform(const char* name) const
{
    auto it = mUniforms.find(name);
    if (it != mUniforms.end()) {
        return it->second;
    }
    GLint location = glGetUniformLocation(mProgram.name(), name);
    mUniforms.emplace(name, location);
    return location;
}

}  // namespace terrain
