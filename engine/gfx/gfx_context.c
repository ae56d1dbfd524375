/* gfx_context.c — choosing a backend, frames, reading pixels back, screenshots. */
#include "gfx_internal.h"

#include "core/core.h"
#include "trace/trace.h"

#include <stb/stb_image_write.h>
#include <stdlib.h>
#include <string.h>

#ifdef ENGINE_DEBUG
static void GLAD_API_PTR gfx_debug_message(GLenum source, GLenum type, GLuint id, GLenum severity,
                                           GLsizei length, const GLchar *message, const void *user) {
    (void)id; (void)length; (void)user;
    if (severity == GL_DEBUG_SEVERITY_NOTIFICATION) return;   /* driver chatter */
    if (source == GL_DEBUG_SOURCE_SHADER_COMPILER) return;     /* printed at file:line instead */
    if (type == GL_DEBUG_TYPE_ERROR) core_log_error("gl", "%s", message);
    else core_warn("gl", "%s", message);
}
#endif

static void gfx_default_state(void) {
#ifdef ENGINE_DEBUG
    /* Route the driver's own diagnostics to our log (GL 4.3 core, KHR_debug). */
    glEnable(GL_DEBUG_OUTPUT);
    glEnable(GL_DEBUG_OUTPUT_SYNCHRONOUS);
    glDebugMessageCallback(gfx_debug_message, NULL);
#endif
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LEQUAL);
    glEnable(GL_CULL_FACE);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
}

static bool gfx_display_present(void) {
    const char *x11 = getenv("DISPLAY"), *wayland = getenv("WAYLAND_DISPLAY");
    return (x11 && *x11) || (wayland && *wayland);
}

gfx_context *gfx_context_create(const gfx_context_desc *desc_in) {
    gfx_context_desc desc = *desc_in;
    if (desc.width <= 0 || desc.height <= 0) { desc.width = 1280; desc.height = 720; }
    if (desc.width > 16384 || desc.height > 16384) {
        core_log_error("gfx", "size %dx%d is larger than 16384x16384", desc.width, desc.height);
        return NULL;
    }
    if (!desc.title) desc.title = "engine";
    gfx_context *gfx = core_calloc(1, sizeof *gfx);
    gfx->open_pass = -1;

    bool window = !desc.headless;
    if (window && !gfx_display_present()) {
        core_info("gfx", "no display (DISPLAY and WAYLAND_DISPLAY unset): rendering offscreen with OSMesa");
        window = false;
    }
    char reason[256] = "";
    if (window && !gfx__window_open(gfx, &desc, reason, sizeof reason)) {
        core_info("gfx", "no window (%s): rendering offscreen with OSMesa", reason);
        window = false;
    }
    if (!window && !gfx__offscreen_open(gfx, desc.width, desc.height)) {
        core_free(gfx, sizeof *gfx);
        return NULL;
    }
    core_debug("gfx", "%s on %s", (const char *)glGetString(GL_VERSION),
               (const char *)glGetString(GL_RENDERER));
    gfx_default_state();
    gfx__resources_init(gfx);
    gfx__timers_init(gfx);
    gfx__programs_init(gfx, desc.shader_dir);
    return gfx;
}

void gfx_context_destroy(gfx_context *gfx) {
    if (!gfx) return;
    gfx__programs_destroy(gfx);
    gfx__timers_destroy(gfx);
    gfx__resources_destroy(gfx);
    if (gfx->backend == GFX_BACKEND_WINDOW) gfx__window_close(gfx);
    else gfx__offscreen_close(gfx);
    core_free(gfx, sizeof *gfx);
}

gfx_backend gfx_backend_get(const gfx_context *gfx) { return gfx->backend; }
void *gfx_glfw_window(const gfx_context *gfx) { return gfx->window; }
uint64_t gfx_frame_index(const gfx_context *gfx) { return gfx->frame_index; }

bool gfx_parse_size(const char *text, int *width, int *height) {
    if (!text) return false;
    char *end;
    long w = strtol(text, &end, 10);
    if (end == text || (*end != 'x' && *end != 'X') || w < 16 || w > 16384) return false;
    const char *second = end + 1;
    if (*second < '0' || *second > '9') return false;
    long h = strtol(second, &end, 10);
    if (*end || h < 16 || h > 16384) return false;
    *width = (int)w;
    *height = (int)h;
    return true;
}

void gfx_size(const gfx_context *gfx, int *width, int *height) {
    *width = gfx->width;
    *height = gfx->height;
}

void gfx_frame_begin(gfx_context *gfx) {
    TRACE_ZONE("gfx_frame_begin");
#ifdef ENGINE_DEBUG
    uint64_t now = core_time_ns();
    if (now >= gfx->next_reload_check_ns) {
        gfx->next_reload_check_ns = now + 500000000ull;
        gfx_programs_reload_changed(gfx);
    }
#endif
    gfx__timers_collect(gfx);
}

/* The next frame's depth clear, queued with the rest of this offscreen frame, which is waited for
 * anyway; the next frame's first pass into the default framebuffer that asks for a depth clear
 * finds it done (gfx_pass_begin). On llvmpipe a clear queued at a frame's start held up that
 * frame's first draws while the driver's threads ran it (engine/gfx/README.md). A window keeps
 * the clear in its pass: EGL leaves the depth buffer undefined after a swap, and the window
 * system may resize it between frames. */
static void gfx_clear_depth_ahead(gfx_context *gfx) {
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDepthMask(GL_TRUE);
    glClearDepth(1.0);
    glClear(GL_DEPTH_BUFFER_BIT);
    gfx->depth_cleared_ahead = true;
}

void gfx_frame_end(gfx_context *gfx) {
    TRACE_ZONE("gfx_frame_end");
    if (gfx->backend == GFX_BACKEND_WINDOW) {
        gfx__window_swap(gfx);
    } else {
        gfx_clear_depth_ahead(gfx);
        /* Offscreen there is no swap to wait on: finish, so a frame's time is the GPU's too. */
        TRACE_ZONE("gpu.wait");
        glFinish();
    }
    gfx->frame_index++;
    gfx->last_frame = gfx__frame_counts;
    gfx__frame_counts = (gfx_context_stats_info){ 0 };
    trace_counter("gfx.draw_calls", gfx->last_frame.draw_calls);
    trace_counter("gfx.triangles", (double)gfx->last_frame.triangles);
    trace_counter("gfx.indirect_draws", gfx->last_frame.indirect_draws);
}

gfx_context_stats_info gfx_context_stats(const gfx_context *gfx) { return gfx->last_frame; }

void gfx_read_pixels(gfx_context *gfx, uint8_t *rgba) {
    TRACE_ZONE("gfx_read_pixels");
    int width = gfx->width, height = gfx->height;
    size_t row = (size_t)width * 4;
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    glReadBuffer(gfx->backend == GFX_BACKEND_WINDOW ? GL_BACK : GL_FRONT);
    glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
    /* GL's rows run bottom-up; images are stored top row first. */
    uint8_t *swap = core_alloc(row);
    for (int y = 0; y < height / 2; y++) {
        uint8_t *top = rgba + (size_t)y * row, *bottom = rgba + (size_t)(height - 1 - y) * row;
        memcpy(swap, top, row);
        memcpy(top, bottom, row);
        memcpy(bottom, swap, row);
    }
    core_free(swap, row);
}

bool gfx_screenshot(gfx_context *gfx, const char *path) {
    size_t size = (size_t)gfx->width * (size_t)gfx->height * 4;
    uint8_t *rgba = core_alloc(size);
    gfx_read_pixels(gfx, rgba);
    /* The framebuffer has no meaningful alpha: write it opaque. */
    for (size_t i = 3; i < size; i += 4) rgba[i] = 255;
    bool ok = gfx_write_png(path, gfx->width, gfx->height, rgba);
    core_free(rgba, size);
    return ok;
}

bool gfx_write_png(const char *path, int width, int height, const uint8_t *rgba) {
    int ok = stbi_write_png(path, width, height, 4, rgba, width * 4);
    if (!ok) core_log_error("gfx", "cannot write the picture %s", path);
    else core_info("gfx", "picture %s (%dx%d)", path, width, height);
    return ok != 0;
}
