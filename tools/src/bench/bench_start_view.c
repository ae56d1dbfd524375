/* bench_start_view.c — the world walk's start view that quality rows compare (bench_start_view.h). */
#include "bench_start_view.h"

#include "core/core.h"

#include <math.h>
#include <string.h>

game_app_desc bench_start_view_desc(const bench_context *ctx) {
    return (game_app_desc){ .seed = 1, .width = 640, .height = 360, .headless = true, .threads = bench_threads(ctx),
                            .frames = 1000000, .no_hud = true,
                            /* world.walk's first view: along +z, the walker's pitch (−0.1 rad) */
                            .look_set = true, .look = { 0, -0.1 * 180 / M_PI } };
}

game_app *bench_start_view_open(const game_app_desc *desc) {
    game_app *app = game_app_create(desc);
    if (!app) return NULL;
    while (!game_app_loaded(app)) game_app_frame(app);
    for (int i = 0; i < 60; i++) game_app_frame(app);
    return app;
}

double bench_start_view_frames(game_app *app, void (*each)(game_app *app, void *user), void *user) {
    uint64_t start = core_time_ns();
    for (int i = 0; i < BENCH_START_VIEW_FRAMES; i++) {
        game_app_frame(app);
        if (each) each(app, user);
    }
    return (double)(core_time_ns() - start) * 1e-6 / BENCH_START_VIEW_FRAMES;
}

double bench_median(const double *samples, int count) {
    double sorted[64];
    if (count > 64) count = 64;
    memcpy(sorted, samples, (size_t)count * sizeof *sorted);
    for (int i = 1; i < count; i++)
        for (int j = i; j > 0 && sorted[j] < sorted[j - 1]; j--) {
            double t = sorted[j];
            sorted[j] = sorted[j - 1], sorted[j - 1] = t;
        }
    return sorted[count / 2];
}
