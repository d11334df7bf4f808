#include "render/GlWindow.h"

// libepoxy must come before GLFW (which would otherwise include the system GL header first).
#include <epoxy/gl.h>

#include <GLFW/glfw3.h>

#include <cstdio>
#include <cstdlib>

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
}  // namespace

bool displayAvailable()
{
    const char* x11 = std::getenv("DISPLAY");
    const char* wayland = std::getenv("WAYLAND_DISPLAY");
    return (x11 && *x11) || (wayland && *wayland);
}

Expected<std::unique_ptr<GlWindow>> GlWindow::create(const WindowOptions& options)
{
    if (!displayAvailable()) {
        return makeError("no display: set DISPLAY, or run headless under Xvfb (xvfb-run -a -s \"-screen 0 ",
                         options.width, "x", options.height, "x24\" ...)");
    }
    if (glfwInit() != GLFW_TRUE) {
        return makeError("cannot initialise GLFW: ", lastGlfwError());
    }
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
    return std::unique_ptr<GlWindow>(new GlWindow(window));
}

GlWindow::~GlWindow()
{
    glfwDestroyWindow(mWindow);
    glfwTerminate();
}

bool GlWindow::shouldClose() const
{
    return glfwWindowShouldClose(mWindow) != 0;
}
void GlWindow::requestClose()
{
    glfwSetWindowShouldClose(mWindow, GLFW_TRUE);
}
void GlWindow::swapBuffers()
{
    glfwSwapBuffers(mWindow);
}
void GlWindow::pollEvents()
{
    glfwPollEvents();
}

int GlWindow::width() const
{
    int w = 0, h = 0;
    glfwGetFramebufferSize(mWindow, &w, &h);
    return w;
}

int GlWindow::height() const
{
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
    return "OpenGL " + text(GL_VERSION) + ", " + text(GL_RENDERER);
}

}  // namespace terrain
