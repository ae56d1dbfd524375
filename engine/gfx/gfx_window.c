/* gfx_window.c — the GLFW backend: a resizable window with vsync, fullscreen toggle and an
 * OpenGL 4.5 core context (a debug context in debug builds). The input system owns the window's
 * input callbacks and user pointer; this file only sizes, swaps and closes it. */
#include "gfx_internal.h"

#include "core/core.h"
#include "trace/trace.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

static int gfx_glfw_users;   /* windows open; GLFW is initialised while this is > 0 */

static void gfx_glfw_error(int code, const char *message) {
    core_warn("glfw", "%s (error 0x%x)", message, code);
}

/* Why the last GLFW call failed, for the one line that says we fall back to OSMesa. */
static void gfx_glfw_failure(char *reason, size_t size) {
    const char *description = NULL;
    glfwGetError(&description);
    snprintf(reason, size, "%s", description ? description : "unknown reason");
}

bool gfx__window_open(gfx_context *gfx, const gfx_context_desc *desc, char *reason, size_t reason_size) {
    /* Errors while opening are reported once, by the caller; later ones go to the log. */
    glfwSetErrorCallback(NULL);
    if (gfx_glfw_users == 0 && !glfwInit()) {
        gfx_glfw_failure(reason, reason_size);
        return false;
    }
    gfx_glfw_users++;
    glfwDefaultWindowHints();
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
#ifdef ENGINE_DEBUG
    glfwWindowHint(GLFW_OPENGL_DEBUG_CONTEXT, GLFW_TRUE);
#endif
    glfwWindowHint(GLFW_RESIZABLE, GLFW_TRUE);
    glfwWindowHint(GLFW_VISIBLE, desc->hidden ? GLFW_FALSE : GLFW_TRUE);
    GLFWmonitor *monitor = desc->fullscreen ? glfwGetPrimaryMonitor() : NULL;
    GLFWwindow *window = glfwCreateWindow(desc->width, desc->height, desc->title, monitor, NULL);
    if (!window) {
        gfx_glfw_failure(reason, reason_size);
        if (--gfx_glfw_users == 0) glfwTerminate();
        return false;
    }
    glfwMakeContextCurrent(window);
    if (!gladLoadGL((GLADloadfunc)glfwGetProcAddress)) {
        snprintf(reason, reason_size, "cannot load OpenGL functions through GLFW");
        glfwDestroyWindow(window);
        if (--gfx_glfw_users == 0) glfwTerminate();
        return false;
    }
    glfwSetErrorCallback(gfx_glfw_error);
    gfx->backend = GFX_BACKEND_WINDOW;
    gfx->window = window;
    gfx->fullscreen = monitor != NULL;
    gfx->windowed_width = desc->width;
    gfx->windowed_height = desc->height;
    glfwGetWindowPos(window, &gfx->windowed_x, &gfx->windowed_y);
    glfwGetFramebufferSize(window, &gfx->width, &gfx->height);
    gfx_window_set_vsync(gfx, !desc->no_vsync);
    return true;
}

void gfx__window_close(gfx_context *gfx) {
    glfwDestroyWindow((GLFWwindow *)gfx->window);
    gfx->window = NULL;
    if (--gfx_glfw_users == 0) glfwTerminate();
}

void gfx__window_swap(gfx_context *gfx) {
    GLFWwindow *window = gfx->window;
    {
        TRACE_ZONE("gpu.wait");     /* the swap waits for the GPU (and vsync) */
        glfwSwapBuffers(window);
    }
    int width, height;
    glfwGetFramebufferSize(window, &width, &height);
    /* A minimised window reports 0 × 0: keep the last real size. */
    if (width > 0 && height > 0) { gfx->width = width; gfx->height = height; }
}

bool gfx_window_should_close(const gfx_context *gfx) {
    return gfx->window && glfwWindowShouldClose((GLFWwindow *)gfx->window);
}

void gfx_window_set_vsync(gfx_context *gfx, bool vsync) {
    if (!gfx->window) return;
    glfwSwapInterval(vsync ? 1 : 0);
    gfx->vsync = vsync;
}

void gfx_window_set_title(gfx_context *gfx, const char *title) {
    if (gfx->window) glfwSetWindowTitle((GLFWwindow *)gfx->window, title);
}

void gfx_window_toggle_fullscreen(gfx_context *gfx) {
    GLFWwindow *window = gfx->window;
    if (!window) return;
    if (gfx->fullscreen) {
        glfwSetWindowMonitor(window, NULL, gfx->windowed_x, gfx->windowed_y, gfx->windowed_width,
                             gfx->windowed_height, 0);
    } else {
        GLFWmonitor *monitor = glfwGetPrimaryMonitor();
        const GLFWvidmode *mode = monitor ? glfwGetVideoMode(monitor) : NULL;
        if (!mode) return;
        glfwGetWindowPos(window, &gfx->windowed_x, &gfx->windowed_y);
        glfwGetWindowSize(window, &gfx->windowed_width, &gfx->windowed_height);
        glfwSetWindowMonitor(window, monitor, 0, 0, mode->width, mode->height, mode->refreshRate);
    }
    gfx->fullscreen = !gfx->fullscreen;
    /* Monitors may reset the swap interval. */
    gfx_window_set_vsync(gfx, gfx->vsync);
}
