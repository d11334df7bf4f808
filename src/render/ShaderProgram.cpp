#include "render/ShaderProgram.h"

#include <algorithm>
#include <fstream>
#include <sstream>

namespace terrain {

namespace {

Expected<std::string> readText(const std::filesystem::path& path)
{
    std::ifstream in(path, std::ios::binary);
    if (!in) {
        return makeError(path.string(), ": cannot read shader");
    }
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
}

/// Inserts the defines after the #version line (which must come first in GLSL).
std::string withDefines(const std::string& source, const std::vector<std::string>& defines)
{
    std::string block;
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

Expected<ShaderProgram> ShaderProgram::fromSource(const std::string& name, const std::string& vertex,
                                                  const std::string& fragment, const std::vector<std::string>& defines)
{
    auto vs = compile(GL_VERTEX_SHADER, name + ".vert", withDefines(vertex, defines));
    TERRAIN_TRY(vs);
    auto fs = compile(GL_FRAGMENT_SHADER, name + ".frag", withDefines(fragment, defines));
    if (!fs.ok()) {
        glDeleteShader(*vs);
        return fs.error();
    }
    ShaderProgram program;
    program.mProgram = gl::Program::create();
    glAttachShader(program.name(), *vs);
    glAttachShader(program.name(), *fs);
    glLinkProgram(program.name());
    glDeleteShader(*vs);
    glDeleteShader(*fs);
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

Expected<ShaderProgram> ShaderProgram::load(const std::filesystem::path& directory, const std::string& name,
                                            const std::vector<std::string>& defines)
{
    auto vertex = readText(directory / (name + ".vert"));
    TERRAIN_TRY(vertex);
    auto fragment = readText(directory / (name + ".frag"));
    TERRAIN_TRY(fragment);
    return fromSource((directory / name).string(), *vertex, *fragment, defines);
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
