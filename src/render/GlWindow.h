// An OpenGL 3.3+ core context and the GL function loader (libepoxy): a window (GLFW) to look at, or, for
// video mode and tests, a headless context with no window system at all (EGL's surfaceless platform, e.g.
// Mesa's llvmpipe with OpenGL 4.5 core) that draws into a framebuffer object of the same size.
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
    /// false: headless (video mode, tests): an EGL context with no window system drawing into a framebuffer
    /// object of width x height; where EGL has no such context, a hidden GLFW window (needs a display).
    bool visible = true;
    std::string title = "tengine";
    bool vsync = false;
    /// A window's display going away (the X server ends, its connection breaks) ends the process, as nothing
    /// more can be drawn or shown: this is called first, once, with a line saying so; then the process exits with
    /// kDisplayLostStatus (the other threads are not joined: whatever must be kept is written as it happens).
    std::function<void(const std::string&)> displayLost;
};

/// The exit status of a process whose window's display went away.
inline constexpr int kDisplayLostStatus = 3;

class GlWindow {
public:
    /// Opens the window (or the headless context) and makes its context current. Fails with a message saying
    /// what is missing (no display, no OpenGL 3.3 core, no headless EGL). One per process.
    static Expected<std::unique_ptr<GlWindow>> create(const WindowOptions& options);
    ~GlWindow();
    GlWindow(const GlWindow&) = delete;
    GlWindow& operator=(const GlWindow&) = delete;

    /// The GLFW window; null when headless (no input, nothing to show).
    GLFWwindow* handle() const { return mWindow; }
    bool headless() const { return mHeadless != nullptr; }
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
    struct Headless;
    explicit GlWindow(GLFWwindow* window);
    explicit GlWindow(std::unique_ptr<Headless> headless);
    static Expected<std::unique_ptr<GlWindow>> createHeadless(const WindowOptions& options);
    GLFWwindow* mWindow = nullptr;
    std::unique_ptr<Headless> mHeadless;
    std::function<void(const std::string&)> mDisplayLost;  ///< WindowOptions::displayLost
    bool mCloseRequested = false;
};

/// True when a display is available for windows (DISPLAY or WAYLAND_DISPLAY set).
bool displayAvailable();

}  // namespace terrain
