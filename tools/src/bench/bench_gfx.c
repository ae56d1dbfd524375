/* bench_gfx.c — frames of the reference scene (gfx_scene: sky, ground grid, lit sphere) through
 * OSMesa's llvmpipe, the software rasteriser the tests and headless runs use. A frame is
 * begin → draw → end, and the offscreen end waits for the GPU (glFinish), so this is the whole
 * cost of a frame, as a headless run sees it. */
#include "bench.h"

#include "core/core.h"
#include "gfx/gfx.h"

#include <stdbool.h>

#define BENCH_GFX_FRAMES_PER_SAMPLE 20

typedef struct gfx_bench {
    gfx_context *gfx;
    gfx_scene *scene;               /* NULL: clear-only frames (the floor under any scene) */
    gfx_camera camera;
    int frame;
} gfx_bench;

static double sample_frames(void *user) {
    gfx_bench *b = user;
    uint64_t start = core_time_ns();
    for (int i = 0; i < BENCH_GFX_FRAMES_PER_SAMPLE; i++, b->frame++) {
        gfx_frame_begin(b->gfx);
        if (b->scene) {
            gfx_scene_draw(b->scene, &b->camera, b->frame / 60.0);
        } else {
            gfx_pass_begin(b->gfx, &(gfx_pass_desc){ .name = "clear", .clear_color = true,
                                                     .color = { 0.5f, 0.7f, 1.0f, 1.0f }, .clear_depth = true });
            gfx_pass_end(b->gfx);
        }
        gfx_frame_end(b->gfx);
    }
    return (double)(core_time_ns() - start) * 1e-6 / BENCH_GFX_FRAMES_PER_SAMPLE;
}

static void bench_frame_size(bench_context *ctx, const char *name, int width, int height, bool scene) {
    if (!bench_wants(ctx, name)) return;
    gfx_bench b = { .camera = gfx_scene_default_camera() };
    b.gfx = gfx_context_create(&(gfx_context_desc){ .width = width, .height = height, .headless = true });
    if (!b.gfx || (scene && !(b.scene = gfx_scene_create(b.gfx)))) {
        core_log_error("bench", "%s: no OpenGL context or scene; row skipped", name);
        gfx_context_destroy(b.gfx);
        return;
    }
    bench_run(ctx, name, "ms", 9, sample_frames, &b);
    gfx_scene_destroy(b.scene);
    gfx_context_destroy(b.gfx);
}

void bench_group_gfx(bench_context *ctx) {
    bench_frame_size(ctx, "gfx.frame.offscreen.640x360", 640, 360, true);
    /* The same frame with nothing drawn: what OSMesa's clear and finish cost on their own. */
    bench_frame_size(ctx, "gfx.frame.offscreen.640x360.clear_only", 640, 360, false);
    bench_frame_size(ctx, "gfx.frame.offscreen.1280x720", 1280, 720, true);
}
