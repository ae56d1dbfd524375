/* game_setup_system — the walkable world with a system of its own: the sun crosses the sky.
 *
 * A game extends the world through game_app_desc.setup, without touching the engine or the game
 * loop: setup runs once the game's systems exist. Here it gives the camera's entity a component,
 * SunClock, and adds a system that turns the camera's sun with the game's clock (the GameClock
 * resource), so the light and the sky change as the player walks. The developer's part is the 19
 * lines between the two rules; the rest is the usual command line.
 *
 *   game_setup_system [--seed N] [--day SECONDS] [--radius R] [--levels N] [--size WxH] [--headless]
 *                     [--frames N] [--screenshot FILE] [--threads N] [--trace FILE]
 */
#include "core/core.h"
#include "game/app.h"
#include "gfx/gfx.h"
#include "trace/trace.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* ------------------------------------------------------------------------------------------ */
typedef struct SunClock { float day_seconds; } SunClock;   /* sunrise to sunset, then again */

static void sun_clock(ecs_iter *it) {                      /* game phase, after `camera` */
    const GameClock *clock = ecs_resource_get(it->world, ((const game_ids *)it->user)->clock);
    while (ecs_query_next(it)) {
        GameCamera *camera = ecs_field(it, 0);
        SunClock *sun = ecs_field(it, 1);
        for (int i = 0; i < it->count; i++) {
            float angle = 3.14159f * (0.1f + 0.8f * fmodf((float)clock->seconds / sun[i].day_seconds, 1.0f));
            memcpy(camera[i].view.sun_direction, (float[3]){ cosf(angle), sinf(angle), 0.3f }, sizeof(float[3]));
        }
    }
}

static void setup(game_app *app, ecs_world *ecs, void *user) {
    const game_ids *ids = game_app_ids(app);
    ecs_component sun = ECS_COMPONENT(ecs, SunClock);
    ecs_set(ecs, game_app_camera(app), sun, &(SunClock){ (float)*(const double *)user });
    ecs_system_add(ecs, &(ecs_system_desc){ .name = "sun_clock", .phase = "game", .query = { .with = { ids->camera, sun } },
        .writes = { ids->camera }, .reads = { ids->clock }, .fn = sun_clock, .user = (void *)ids });
}
/* ------------------------------------------------------------------------------------------ */

int main(int argc, char **argv) {
    core_common_args common = { 0 };
    const char *size = NULL, *screenshot = NULL;
    int frames = 0, seed = 1, radius = 0, levels = 0;
    double day_seconds = 20.0;
    bool headless = false;
    const core_option options[] = {
        CORE_COMMON_OPTIONS(common),
        { "seed", CORE_OPTION_INT, &seed, "N", "world seed (default 1)", 0, 1000000000 },
        { "day", CORE_OPTION_DOUBLE, &day_seconds, "SECONDS", "sunrise to sunset (default 20)", .min_double = 1,
          .max_double = 100000 },
        { "radius", CORE_OPTION_INT, &radius, "R", "full-detail chunks of 32 m each way (default 2)", 1, 32 },
        { "levels", CORE_OPTION_INT, &levels, "N", "rings of volumetric detail (default 3)", 1, 8 },
        { "size", CORE_OPTION_STRING, &size, "WxH", "framebuffer size (default 1280x720)" },
        { "headless", CORE_OPTION_FLAG, &headless, NULL, "render offscreen with OSMesa" },
        { "frames", CORE_OPTION_INT, &frames, "N", "stop after N frames past loading (0 = when closed)", 0, 100000000 },
        { "screenshot", CORE_OPTION_STRING, &screenshot, "FILE", "write the last frame as a PNG" },
    };
    core_cli cli = { .program = "game_setup_system", .summary = "the walkable world with a sun that crosses the sky, a system of its own",
                     .options = options, .option_count = CORE_COUNTOF(options) };
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    int width = 1280, height = 720;
    if (size && !gfx_parse_size(size, &width, &height)) {
        fprintf(stderr, "game_setup_system: bad value for '--size'\n");
        core_cli_print_usage(&cli, stderr);
        return 2;
    }
    if (common.trace_path && !trace_start(common.trace_path)) return 2;
    trace_thread_name("main");
    /* Rock piles and cliff blocks off: their tiles take seconds to build each run (the world
     * program caches them in out/), and this example is about the system. */
    game_app *app = game_app_create(&(game_app_desc){
        .seed = (uint64_t)seed, .width = width, .height = height, .headless = headless, .threads = common.threads,
        .frames = frames, .screenshot_path = screenshot, .stream = { .half_width = radius, .levels = levels }, .rocks = ROCKS_OFF, .cliffs = ROCKS_OFF, .setup = setup, .setup_user = &day_seconds });
    if (!app) return 1;
    while (game_app_frame(app)) {}
    game_app_stats_info stats = game_app_stats(app);
    const GameCamera *camera = ecs_get(game_app_ecs(app), game_app_camera(app), game_app_ids(app)->camera);
    printf("game_setup_system: %d frames, the sun at %.0f degrees over the horizon\n", stats.frames,
           asin(camera->view.sun_direction[1] / sqrt(1.0 + 0.09)) * 180.0 / 3.14159265358979);
    game_app_destroy(app);
    trace_stop();
    return 0;
}

/* Expected output:
 * Run: --headless --size 64x48 --radius 1 --levels 1 --frames 30 --day 1
 * ^game_setup_system: 30 frames, the sun at 73 degrees over the horizon$
 */
