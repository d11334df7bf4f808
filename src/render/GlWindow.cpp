#include "render/GlWindow.h"

// libepoxy must come before GLFW (which would otherwise include the system GL header first).
#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include <GLFW/glfw3.h>
#include <X11/Xlib.h>

#include <cstdio>
#include <cstdlib>
#include <string>

namespace terrain {

namespace {
/// GLFW's last error on this thread, as text (glfwGetError: no callback, no global state of ours).
std::string lastGlfwError()
{
    const char* description = nullptr;
    int code = glfwGetError(&description);
    return code == GLFW_NO_ERROR ? "no details"
                                 : "GLFW error " + std::to_string(code) + ": " + (description ? description : "");
}

#ifndef NDEBUG
void GLAPIENTRY onGlDebugMessage(GLenum, GLenum type, GLuint, GLenum severity, GLsizei, const GLchar* message,
                                 const void*)
{
    if (severity == GL_DEBUG_SEVERITY_HIGH || type == GL_DEBUG_TYPE_ERROR) {
        std::fprintf(stderr, "OpenGL: %s\n", message);
    }
}
#endif

/// What the window's creator asked to be told when its display goes away. Xlib's handler of a broken connection
/// is the process's, and a process has one window: set while it exists.
std::function<void(const std::string&)>* gDisplayLost = nullptr;

/// Xlib's handler of a broken connection (the default prints and calls exit(), whose destructors would race the
/// worker threads): says so, then ends the process at once.
int onDisplayLost(Display* display)
{
    const char* name = display ? DisplayString(display) : nullptr;
    const std::string line = std::string("the display ") + (name ? name : "") +
                             " went away (the X server ended or the connection to it broke): ending";
    if (gDisplayLost && *gDisplayLost) {
        (*gDisplayLost)(line);
    } else {
        std::fprintf(stderr, "%s\n", line.c_str());
    }
    std::fflush(nullptr);
    std::_Exit(kDisplayLostStatus);
}

}  // namespace

bool displayAvailable()
{
    const char* x11 = std::getenv("DISPLAY");
    const char* wayland = std::getenv("WAYLAND_DISPLAY");
    return (x11 && *x11) || (wayland && *wayland);
}

/// The headless context: EGL display and context, and the framebuffer object drawn into.
struct GlWindow::Headless {
    EGLDisplay display = EGL_NO_DISPLAY;
    EGLContext context = EGL_NO_CONTEXT;
    GLuint framebuffer = 0;
    GLuint colour = 0;
    GLuint depth = 0;
    int width = 0;
    int height = 0;

    ~Headless()
    {
        if (framebuffer != 0) {
            glDeleteFramebuffers(1, &framebuffer);
            glDeleteRenderbuffers(1, &colour);
            glDeleteRenderbuffers(1, &depth);
        }
        if (display != EGL_NO_DISPLAY) {
            eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
            if (context != EGL_NO_CONTEXT) {
                eglDestroyContext(display, context);
            }
            eglTerminate(display);
        }
    }
};

GlWindow::GlWindow(std::unique_ptr<Headless> headless) : mHeadless(std::move(headless)) {}
GlWindow::GlWindow(GLFWwindow* window) : mWindow(window) {}

Expected<std::unique_ptr<GlWindow>> GlWindow::createHeadless(const WindowOptions& options)
{
    if (!epoxy_has_egl()) {
        return makeError("no EGL library (libEGL.so.1: Debian's libegl1 and libegl-mesa0)");
    }
    auto h = std::make_unique<Headless>();
    h->width = options.width;
    h->height = options.height;
    if (!epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_MESA_platform_surfaceless") ||
        !epoxy_has_egl_extension(EGL_NO_DISPLAY, "EGL_EXT_platform_base")) {
        return makeError("EGL has no surfaceless platform (EGL_MESA_platform_surfaceless)");
    }
    // The extension's entry point: the core one (EGL 1.5) cannot be looked up before there is a display.
    h->display = eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    EGLint major = 0, minor = 0;
    if (h->display == EGL_NO_DISPLAY || eglInitialize(h->display, &major, &minor) != EGL_TRUE) {
        h->display = EGL_NO_DISPLAY;
        return makeError("cannot initialise EGL's surfaceless display (EGL error 0x", std::hex, eglGetError(), ")");
    }
    if (eglBindAPI(EGL_OPENGL_API) != EGL_TRUE) {
        return makeError("EGL has no desktop OpenGL");
    }
    // The same request as the window's: 3.3 core, which Mesa answers with its highest core version.
    const EGLint attributes[] = {EGL_CONTEXT_MAJOR_VERSION,
                                 3,
                                 EGL_CONTEXT_MINOR_VERSION,
                                 3,
                                 EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                 EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
#ifndef NDEBUG
                                 EGL_CONTEXT_OPENGL_DEBUG,
                                 EGL_TRUE,
#endif
                                 EGL_NONE};
    h->context = eglCreateContext(h->display, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attributes);
    if (h->context == EGL_NO_CONTEXT) {
        return makeError("cannot create an OpenGL 3.3 core context with EGL (EGL error 0x", std::hex, eglGetError(),
                         ")");
    }
    if (eglMakeCurrent(h->display, EGL_NO_SURFACE, EGL_NO_SURFACE, h->context) != EGL_TRUE) {
        return makeError("cannot make the EGL context current without a surface (EGL error 0x", std::hex, eglGetError(),
                         ")");
    }
    // What the window's default framebuffer has: 8-bit colour, 24-bit depth with stencil.
    glGenFramebuffers(1, &h->framebuffer);
    glGenRenderbuffers(1, &h->colour);
    glGenRenderbuffers(1, &h->depth);
    glBindRenderbuffer(GL_RENDERBUFFER, h->colour);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, options.width, options.height);
    glBindRenderbuffer(GL_RENDERBUFFER, h->depth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH24_STENCIL8, options.width, options.height);
    glBindRenderbuffer(GL_RENDERBUFFER, 0);
    glBindFramebuffer(GL_FRAMEBUFFER, h->framebuffer);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, h->colour);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_RENDERBUFFER, h->depth);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
        return makeError("cannot make a ", options.width, "x", options.height, " framebuffer to draw into headless");
    }
    glDrawBuffer(GL_COLOR_ATTACHMENT0);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
#ifndef NDEBUG
    if (epoxy_gl_version() >= 43) {
        glEnable(GL_DEBUG_OUTPUT);
        glDebugMessageCallback(onGlDebugMessage, nullptr);
    }
#endif
    return std::unique_ptr<GlWindow>(new GlWindow(std::move(h)));
}

Expected<std::unique_ptr<GlWindow>> GlWindow::create(const WindowOptions& options)
{
    std::string headlessError;
    if (!options.visible) {
        auto headless = createHeadless(options);
        if (headless.ok()) {
            return headless;
        }
        headlessError = headless.error().message;
    }
    if (!displayAvailable()) {
        if (!headlessError.empty()) {
            return makeError("no headless OpenGL (", headlessError, ") and no display for a window (set DISPLAY)");
        }
        return makeError("no display: set DISPLAY, or run headless under Xvfb (xvfb-run -a -s \"-screen 0 ",
                         options.width, "x", options.height, "x24\" ...)");
    }
    if (glfwInit() != GLFW_TRUE) {
        return makeError("cannot initialise GLFW: ", lastGlfwError());
    }
    // GLFW talks to X through Xlib; a Wayland build never calls this handler.
    XSetIOErrorHandler(onDisplayLost);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_VISIBLE, options.visible ? GLFW_TRUE : GLFW_FALSE);
    glfwWindowHint(GLFW_RESIZABLE, GLFW_FALSE);
    glfwWindowHint(GLFW_SAMPLES, 0);
#ifndef NDEBUG
    glfwWindowHint(GLFW_OPENGL_DEBUG_CONTEXT, GLFW_TRUE);
#endif
    GLFWwindow* window = glfwCreateWindow(options.width, options.height, options.title.c_str(), nullptr, nullptr);
    if (!window) {
        std::string reason = lastGlfwError();
        glfwTerminate();
        return makeError("cannot open a ", options.width, "x", options.height,
                         " window with an OpenGL 3.3 core context: ", reason);
    }
    glfwMakeContextCurrent(window);
    glfwSwapInterval(options.vsync ? 1 : 0);
#ifndef NDEBUG
    if (epoxy_gl_version() >= 43) {
        glEnable(GL_DEBUG_OUTPUT);
        glDebugMessageCallback(onGlDebugMessage, nullptr);
    }
#endif
    std::unique_ptr<GlWindow> created(new GlWindow(window));
    created->mDisplayLost = options.displayLost;
    gDisplayLost = &created->mDisplayLost;
    return created;
}

GlWindow::~GlWindow()
{
    if (mWindow) {
        gDisplayLost = nullptr;
        glfwDestroyWindow(mWindow);
        glfwTerminate();
    }
}

bool GlWindow::shouldClose() const
{
    return mWindow ? glfwWindowShouldClose(mWindow) != 0 : mCloseRequested;
}
void GlWindow::requestClose()
{
    if (mWindow) {
        glfwSetWindowShouldClose(mWindow, GLFW_TRUE);
    }
    mCloseRequested = true;
}
void GlWindow::swapBuffers()
{
    if (mWindow) {
        glfwSwapBuffers(mWindow);
    } else {
        glFlush();  // nothing to show; the frame stays in the framebuffer object until the next one
    }
}
void GlWindow::pollEvents()
{
    if (mWindow) {
        glfwPollEvents();
    }
}

int GlWindow::width() const
{
    if (mHeadless) {
        return mHeadless->width;
    }
    int w = 0, h = 0;
    glfwGetFramebufferSize(mWindow, &w, &h);
    return w;
}

int GlWindow::height() const
{
    if (mHeadless) {
        return mHeadless->height;
    }
    int w = 0, h = 0;
    glfwGetFramebufferSize(mWindow, &w, &h);
    return h;
}

std::string GlWindow::description() const
{
    auto text = [](GLenum what) {
        const auto* s = reinterpret_cast<const char*>(glGetString(what));
        return std::string(s ? s : "?");
    };
    return "OpenGL " + text(GL_VERSION) + ", " + text(GL_RENDERER) + (mHeadless ? ", headless (EGL)" : "");
}

}  // namespace terrain
