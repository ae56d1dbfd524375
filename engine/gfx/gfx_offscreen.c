/* gfx_offscreen.c — the OSMesa backend: OpenGL 4.5 core rendered by llvmpipe into memory.
 * Used for headless runs, tests and benchmarks; the drawing code does not know the difference. */
#include "gfx_internal.h"

#include "core/core.h"

/* glad's header came first (through gfx_internal.h), so osmesa.h's own include of GL/gl.h is
 * skipped and both agree on the GL types. */
#include <GL/osmesa.h>

static GLADapiproc gfx_osmesa_proc(const char *name) {
    return (GLADapiproc)OSMesaGetProcAddress(name);
}

bool gfx__offscreen_open(gfx_context *gfx, int width, int height) {
    const int attributes[] = {
        OSMESA_FORMAT, OSMESA_RGBA,
        OSMESA_DEPTH_BITS, 24,
        OSMESA_STENCIL_BITS, 8,
        OSMESA_PROFILE, OSMESA_CORE_PROFILE,
        OSMESA_CONTEXT_MAJOR_VERSION, 4,
        OSMESA_CONTEXT_MINOR_VERSION, 5,
        0,
    };
    OSMesaContext context = OSMesaCreateContextAttribs(attributes, NULL);
    if (!context) {
        core_log_error("gfx", "OSMesa cannot make an OpenGL 4.5 core context (Mesa too old?)");
        return false;
    }
    size_t size = (size_t)width * (size_t)height * 4;
    uint8_t *pixels = core_alloc(size);
    if (!OSMesaMakeCurrent(context, pixels, GL_UNSIGNED_BYTE, width, height)) {
        core_log_error("gfx", "OSMesa cannot use a %dx%d framebuffer", width, height);
        OSMesaDestroyContext(context);
        core_free(pixels, size);
        return false;
    }
    if (!gladLoadGL(gfx_osmesa_proc)) {
        core_log_error("gfx", "cannot load OpenGL functions through OSMesa");
        OSMesaDestroyContext(context);
        core_free(pixels, size);
        return false;
    }
    gfx->backend = GFX_BACKEND_OFFSCREEN;
    gfx->osmesa = context;
    gfx->osmesa_pixels = pixels;
    gfx->width = width;
    gfx->height = height;
    return true;
}

void gfx__offscreen_close(gfx_context *gfx) {
    OSMesaMakeCurrent(NULL, NULL, 0, 0, 0);
    OSMesaDestroyContext((OSMesaContext)gfx->osmesa);
    core_free(gfx->osmesa_pixels, (size_t)gfx->width * (size_t)gfx->height * 4);
    gfx->osmesa = NULL;
    gfx->osmesa_pixels = NULL;
}
