// Thin RAII wrappers over OpenGL object names (docs/design.md, "GL code"): move-only, one type per kind of
// object, so a texture cannot be passed where a buffer is expected. Requires a current GL context for
// construction and destruction.
#pragma once

#include <epoxy/gl.h>

#include <utility>

namespace terrain::gl {

/// Owns one GL object name; `Traits` says how to create and delete it.
template <class Traits>
class Object {
public:
    Object() = default;
    static Object create()
    {
        Object o;
        o.mName = Traits::create();
        return o;
    }
    Object(Object&& other) noexcept : mName(std::exchange(other.mName, 0)) {}
    Object& operator=(Object&& other) noexcept
    {
        if (this != &other) {
            reset();
            mName = std::exchange(other.mName, 0);
        }
        return *this;
    }
    Object(const Object&) = delete;
    Object& operator=(const Object&) = delete;
    ~Object() { reset(); }

    GLuint name() const { return mName; }
    explicit operator bool() const { return mName != 0; }
    void reset()
    {
        if (mName != 0) {
            Traits::destroy(mName);
            mName = 0;
        }
    }

private:
    GLuint mName = 0;
};

struct BufferTraits {
    static GLuint create()
    {
        GLuint n = 0;
        glGenBuffers(1, &n);
        return n;
    }
    static void destroy(GLuint n) { glDeleteBuffers(1, &n); }
};
struct VertexArrayTraits {
    static GLuint create()
    {
        GLuint n = 0;
        glGenVertexArrays(1, &n);
        return n;
    }
    static void destroy(GLuint n) { glDeleteVertexArrays(1, &n); }
};
struct TextureTraits {
    static GLuint create()
    {
        GLuint n = 0;
        glGenTextures(1, &n);
        return n;
    }
    static void destroy(GLuint n) { glDeleteTextures(1, &n); }
};
struct FramebufferTraits {
    static GLuint create()
    {
        GLuint n = 0;
        glGenFramebuffers(1, &n);
        return n;
    }
    static void destroy(GLuint n) { glDeleteFramebuffers(1, &n); }
};
struct ShaderTraits;  // shaders are created with a type: see Shader below
struct ProgramTraits {
    static GLuint create() { return glCreateProgram(); }
    static void destroy(GLuint n) { glDeleteProgram(n); }
};

using Buffer = Object<BufferTraits>;
using VertexArray = Object<VertexArrayTraits>;
using Texture = Object<TextureTraits>;
using Framebuffer = Object<FramebufferTraits>;
using Program = Object<ProgramTraits>;

/// Owns a fence (glFenceSync): set after the commands it follows, signalled once the GL has finished them.
class Fence {
public:
    Fence() = default;
    /// A fence after every command issued so far.
    static Fence place()
    {
        Fence f;
        f.mSync = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
        return f;
    }
    Fence(Fence&& other) noexcept : mSync(std::exchange(other.mSync, nullptr)) {}
    Fence& operator=(Fence&& other) noexcept
    {
        if (this != &other) {
            reset();
            mSync = std::exchange(other.mSync, nullptr);
        }
        return *this;
    }
    Fence(const Fence&) = delete;
    Fence& operator=(const Fence&) = delete;
    ~Fence() { reset(); }

    explicit operator bool() const { return mSync != nullptr; }
    /// Waits until the GL has finished the commands before the fence (flushing them first); false if that
    /// takes longer than `nanoseconds` or the wait fails.
    bool wait(GLuint64 nanoseconds) const
    {
        const GLenum r = glClientWaitSync(mSync, GL_SYNC_FLUSH_COMMANDS_BIT, nanoseconds);
        return r == GL_ALREADY_SIGNALED || r == GL_CONDITION_SATISFIED;
    }
    void reset()
    {
        if (mSync != nullptr) {
            glDeleteSync(mSync);
            mSync = nullptr;
        }
    }

private:
    GLsync mSync = nullptr;
};

}  // namespace terrain::gl
