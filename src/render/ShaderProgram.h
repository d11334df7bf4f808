// GLSL programs from the files in shaders/ (docs/design.md, "GL code": shaders are real files; variants by prepending
// #defines, shared code by `#include "name"`; a compile or link failure returns the info log as an error).
#pragma once

#include "core/Expected.h"
#include "gpudata/ShaderFile.h"
#include "render/GlObjects.h"

#include <filesystem>
#include <string>
#include <unordered_map>
#include <vector>

namespace terrain {

class ShaderProgram {
public:
    /// Compiles `<directory>/<name>.vert` and `.frag` with `defines` ("NAME" or "NAME VALUE") inserted after
    /// the #version line, and links them. Errors name the file and carry the driver's log. With `feedback`, those
    /// outputs of the vertex program are captured by transform feedback (interleaved), as loadTessellation's.
    static Expected<ShaderProgram> load(const std::filesystem::path& directory, const std::string& name,
                                        const std::vector<std::string>& defines = {},
                                        const std::vector<std::string>& feedback = {});
    /// Same from source text; `name` is used in messages.
    static Expected<ShaderProgram> fromSource(const std::string& name, const std::string& vertex,
                                              const std::string& fragment,
                                              const std::vector<std::string>& defines = {});

    /// The tessellation program: `<directory>/<vertex>.vert`, `<name>.tesc`, `<name>.tese` and `<name>.frag`.
    /// With `feedback`, those outputs of the last geometry stage are captured by transform feedback
    /// (interleaved), for tests that read back what was generated.
    static Expected<ShaderProgram> loadTessellation(const std::filesystem::path& directory, const std::string& vertex,
                                                    const std::string& name,
                                                    const std::vector<std::string>& defines = {},
                                                    const std::vector<std::string>& feedback = {});

    void use() const { glUseProgram(mProgram.name()); }
    /// Location of a uniform, cached; -1 when the program has none of that name (optimised away).
    GLint uniform(const char* name) const;
    GLuint name() const { return mProgram.name(); }

private:
    struct Stage {
        GLenum type;
        std::string file;
        std::string source;
    };
    static Expected<ShaderProgram> link(const std::string& name, const std::vector<Stage>& stages,
                                        const std::vector<std::string>& defines,
                                        const std::vector<std::string>& feedback);
    gl::Program mProgram;
    mutable std::unordered_map<std::string, GLint> mUniforms;
};

}  // namespace terrain
