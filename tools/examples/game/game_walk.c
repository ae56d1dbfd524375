/* game_walk — a scripted walk through the walkable world (game/walk.h, game/app.h):
 *
 * A walk script is a few lines of waypoints (what `world --walk FILE` reads): parsed with
 * game_walk_parse_text, it becomes the player's input frame by frame, so a headless run walks
 * the world as a player would, the same way every time. Here a short walk of two waypoints,
 * relative to where the player stands, is walked in a tiny world without rocks, grass or water
 * (they take seconds to make in a debug build), and the program prints where the player ended.
 *
 *   game_walk [--seed N] [--hills] [--size WxH] [--headless] [--screenshot FILE] [--threads N]
 *             [--trace FILE]
 *
 * The check runs it over --hills, hand-made ground that streams in at once: generated chunks
 * take a few hundred ms each to make in a debug build.
 *
 * A script with a mistake fails as a whole, naming its line ("lap.walk:3: z: 'ten' is not a number").
 */
#include "core/core.h"
#include "game/app.h"
#include "game/walk.h"
#include "gfx/gfx.h"
#include "trace/trace.h"

#include <math.h>
#include <stdio.h>

static const char lap[] =
    "# a short walk, starting where the player stands\n"
    "relative          # offsets from the start, world axes (X Z in metres)\n"
    "radius 1          # a waypoint counts as reached within 1 m\n"
    "3 0     walk\n"
    "3 4     jump\n";

/* --hills: a world made by hand (game_app_desc.generate), one layer of bedrock a column over
 * gentle hills, instead of the generator's: it streams in at once even in a debug build. */
static void hill_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    (void)user;
    double height = 2.0 * sin((double)x * 0.1) + 1.0 * cos((double)z * 0.08);
    terrain_stacks_builder_push(builder, TERRAIN_BEDROCK, (float)(height - TERRAIN_FLOOR_Y));
}
static terrain_stacks *hills(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, hill_column, user);
}

int main(int argc, char **argv) {
    core_common_args common = { 0 };
    const char *size = NULL, *screenshot = NULL;
    int seed = 5;
    bool headless = false, hand_made = false;
    const core_option options[] = {
        CORE_COMMON_OPTIONS(common),
        { "seed", CORE_OPTION_INT, &seed, "N", "world seed (default 5)", 0, 1000000000 },
        { "size", CORE_OPTION_STRING, &size, "WxH", "framebuffer size (default 320x180)" },
        { "hills", CORE_OPTION_FLAG, &hand_made, NULL, "gentle hills made by hand instead of the generator's world" },
        { "headless", CORE_OPTION_FLAG, &headless, NULL, "render offscreen with OSMesa" },
        { "screenshot", CORE_OPTION_STRING, &screenshot, "FILE", "write the last frame as a PNG" },
    };
    core_cli cli = { .program = "game_walk", .summary = "a scripted walk, parsed and walked headless",
                     .options = options, .option_count = CORE_COUNTOF(options) };
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    int width = 320, height = 180;
    if (size && !gfx_parse_size(size, &width, &height)) {
        fprintf(stderr, "game_walk: bad value for '--size': '%s' is not WxH\n", size);
        core_cli_print_usage(&cli, stderr);
        return 2;
    }
    if (common.trace_path && !trace_start(common.trace_path)) return 2;
    trace_thread_name("main");

    /* The script, parsed: it names its own lines in errors ("lap.walk:3: ..."). */
    game_walk walk;
    core_error error = { 0 };
    if (!game_walk_parse_text(lap, sizeof lap - 1, "lap.walk", &walk, &error)) {
        fprintf(stderr, "game_walk: %s\n", error.message);
        return 1;
    }
    printf("game_walk: lap.walk has %d waypoints, %s\n", walk.count,
           walk.frame == GAME_WALK_RELATIVE ? "relative to the start" : "absolute");

    /* The world, as small as it goes: one ring of 2 × 2 full-detail chunks, no far terrain, and
     * offscreen a frame steps 1/20 s of game time (the walker is the same at any frame rate). */
    game_app *app = game_app_create(&(game_app_desc){
        .seed = (uint64_t)seed, .generate = hand_made ? hills : NULL, .step_seconds = 1.0f / 20.0f, .width = width, .height = height, .headless = headless, .threads = common.threads,
        .walk = &walk, .screenshot_path = screenshot, .stream = { .half_width = 1, .levels = 1 },
        .no_clipmap = true, .no_hud = true, .grass = GRASS_OFF, .water = TERRAIN_WATER_OFF,
        .shadows = TERRAIN_SHADOWS_OFF, .rocks = ROCKS_OFF, .cliffs = ROCKS_OFF });
    if (!app) return 1;
    game_app_stats_info start = game_app_stats(app);
    while (game_app_frame(app)) {}                 /* until the walk ends */
    game_app_stats_info stats = game_app_stats(app);
    double dx = stats.feet[0] - start.feet[0], dz = stats.feet[2] - start.feet[2];
    printf("game_walk: walked %.1f m in %d frames, %s, %.1f m along x and %.1f m along z from the start\n",
           stats.walked, stats.frames, stats.walk_stuck ? "stuck" : "arrived", dx, dz);
    game_app_destroy(app);
    game_walk_free(&walk);
    trace_stop();
    return 0;
}

/* Expected output:
 * Run: --hills --headless --size 32x24 --threads 2
 * ^game_walk: lap.walk has 2 waypoints, relative to the start$
 * ^game_walk: walked [0-9.]+ m in [0-9]+ frames, arrived, [2-4]\.[0-9] m along x and [3-5]\.[0-9] m along z from the start$
 */
