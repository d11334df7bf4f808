// A window with an OpenGL 3.3+ core context (GLFW) and the GL function loader (libepoxy). Headless runs
// use it under Xvfb, where Mesa's llvmpipe provides OpenGL 4.5 core.
#pragma once

#include "core/Expected.h"

#include <functional>
#include <memory>
#include <string>

struct GLFWwindow;

namespace terrain {

struct WindowOptions {
    int width = 1280;
    int height = 720;
    bool visible = true;  ///< false: an offscreen-sized hidden window (video mode, tests)
    std::string title = "tengine";
    bool vsync = false;
};

class GlWindow {
public:
    /// Initialises GLFW, opens the window and makes its context current. Fails with a message saying what
    /// is missing (no display, no OpenGL 3.3 core). One window per process.
    static Expected<std::unique_ptr<GlWindow>> create(const WindowOptions& options);
    ~GlWindow();
    GlWindow(const GlWindow&) = delete;
    GlWindow& operator=(const GlWindow&) = delete;

    GLFWwindow* handle() const { return mWindow; }
    bool shouldClose() const;
    void requestClose();
    void swapBuffers();
    void pollEvents();
    /// Framebuffer size in pixels.
    int width() const;
    int height() const;
    /// "OpenGL 4.5 (Core Profile) Mesa 22.3.6, llvmpipe (LLVM 15.0.6, 256 bits)".
    std::string description() const;

private:
    explicit GlWindow(GLFWwindow* window) : mWindow(window) {}
    GLFWwindow* mWindow = nullptr;
};

/// True when a display is available for windows (DISPLAY or WAYLAND_DISPLAY set).
bool displayAvailable();

}  // namespace terrain
