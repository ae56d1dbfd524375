/* world — the walkable infinite world (game/app.h) on the command line.
 *
 *   world [--seed S] [--size WxH] [--headless] [--frames N] [--walk SCRIPT | --tour] [--record FILE]
 *         [--replay FILE] [--bindings FILE] [--gamepad-mappings FILE] [--screenshot FILE] [--pixel-error P]
 *         [--radius R] [--levels N] [--simplify none|coarse|all]
 *         [--memory MB] [--grass off|low|high] [--water off|low|medium|high] [--shadows off|low|high]
 *         [--detail on|off] [--rocks on|off] [--threads N]
 *         [--trace FILE [--trace-frames N]] [--world DIR] [--at X,Y,Z] [--look YAW,PITCH]
 *
 * In a window: WASD or the left stick to walk, the mouse (click to capture, Escape to let go) or
 * the right stick to look, Space to jump, Shift to sprint, Ctrl or C to crouch, F to fly, F11
 * fullscreen, F12 a screenshot (a new dated file in screenshots/, never over another). Terrain tools: left and right mouse buttons (or the triggers)
 * use the tool on the HUD where the view meets the ground, Tab (right shoulder) picks the next
 * one; --world DIR keeps the edits across runs. Without a display it renders offscreen; give it --frames or a
 * --walk so it ends. At the end it prints what happened: frames, the walk, CPU frame times,
 * streaming counts and memory, and where the player stands and looks.
 *
 * --at X,Y,Z puts the eye there (metres; flying where standing would move it: in the ground or
 * above a drop) and --look YAW,PITCH turns the view (degrees: yaw 0 along +z, positive to the
 * right, i.e. towards −x; pitch up, within ±89), over a walk's start and a world folder's saved
 * pose; the view stays exactly so until input moves it. The HUD shows both, to copy a view:
 *     world --headless --frames 1 --at 10,80,20 --look 90,-20 --screenshot view.png
 */
#include "app.h"

#include "core/core.h"
#include "gfx/gfx.h"
#include "trace/trace.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* The default screen-space error target, pixels: 0, the fixed rings. A target of 3 px drew about
 * 4× the chunk triangles of the fixed rings at both 640×360 and 1280×720 (the fixed rings are
 * coarser than any target allows, because they are centred on the coarsest grid and the finest
 * ring's edge can come up to the eye), doubling the frame on llvmpipe; the counts and pictures are
 * in modules/terrain/README.md, "Detail from a screen-space error". */
#define APP_PIXEL_ERROR 0.0
#define APP_PIXEL_ERROR_TEXT "0"

typedef struct options {
    core_common_args common;
    const char *size, *screenshot, *walk, *record, *replay, *bindings, *gamepad_mappings, *world, *grass, *water, *shadows, *detail, *at,
        *look, *rocks, *cliffs, *simplify;
    int seed, frames, radius, levels, memory_mb, trace_frames;
    double pixel_error;
    bool headless, tour, no_head_bob, no_ao;
} options;

/* `text` as count finite numbers, comma-separated with nothing after them, each within
 * ±limits[n]; false with the problem (naming the number) in `problem`. */
static bool parse_numbers(const char *text, int count, const char *form, const char *const *names,
                          const double *limits, double *out, char *problem, size_t size) {
    const char *p = text;
    for (int n = 0; n < count; n++) {
        char *end;
        out[n] = strtod(p, &end);
        if (end == p || *end != (n + 1 < count ? ',' : '\0')) {
            snprintf(problem, size, "'%s' is not %s (numbers separated by commas)", text, form);
            return false;
        }
        if (!isfinite(out[n])) {
            snprintf(problem, size, "'%s': %s is not a finite number", text, names[n]);
            return false;
        }
        if (fabs(out[n]) > limits[n]) {
            snprintf(problem, size, "'%s': %s is beyond ±%g", text, names[n], limits[n]);
            return false;
        }
        p = end + 1;
    }
    return true;
}

static int bad_value(const core_cli *cli, const char *flag, const char *problem) {
    fprintf(stderr, "world: bad value for '--%s': %s\n", flag, problem);
    core_cli_print_usage(cli, stderr);
    return 2;
}

static int parse(int argc, char **argv, options *o, game_app_desc *desc, game_walk *walk) {
    const core_option list[] = {
        CORE_COMMON_OPTIONS(o->common),
        { "trace-frames", CORE_OPTION_INT, &o->trace_frames, "N", "with --trace: keep only the last N frames "
          "(a ring, for long runs; 0 = all)", 0, 100000000 },
        { "seed", CORE_OPTION_INT, &o->seed, "S", "world seed (default 1, or the --world folder's)", 0,
          2147483647 },
        { "world", CORE_OPTION_STRING, &o->world, "DIR", "keep the world's edits in DIR (loaded, autosaved)" },
        { "size", CORE_OPTION_STRING, &o->size, "WxH", "framebuffer size (default 1280x720)" },
        { "headless", CORE_OPTION_FLAG, &o->headless, NULL, "render offscreen with OSMesa" },
        { "no-head-bob", CORE_OPTION_FLAG, &o->no_head_bob, NULL, "keep the view level while walking" },
        { "no-ao", CORE_OPTION_FLAG, &o->no_ao, NULL, "light the terrain without its ambient occlusion" },
        { "frames", CORE_OPTION_INT, &o->frames, "N", "stop after N frames past loading (0 = when closed)", 0,
          100000000 },
        { "walk", CORE_OPTION_STRING, &o->walk, "SCRIPT", "scripted walk: " GAME_WALK_USAGE },
        { "tour", CORE_OPTION_FLAG, &o->tour, NULL, "the built-in tour: pictures on foot and from above "
          "(with --screenshot FILE: FILE-N.png and FILE side by side)" },
        { "record", CORE_OPTION_STRING, &o->record, "FILE", "record every frame's input" },
        { "replay", CORE_OPTION_STRING, &o->replay, "FILE", "play recorded input back" },
        { "bindings", CORE_OPTION_STRING, &o->bindings, "FILE", "input bindings (data/input/bindings.txt)" },
        { "gamepad-mappings", CORE_OPTION_STRING, &o->gamepad_mappings, "FILE",
          "SDL game controller database lines for pads read through GLFW (bad lines are reported and skipped)" },
        { "screenshot", CORE_OPTION_STRING, &o->screenshot, "FILE", "write the last frame as a PNG" },
        { "pixel-error", CORE_OPTION_DOUBLE, &o->pixel_error, "P", "detail by screen-space error: rings and far "
          "terrain fine enough for P pixels at the window's size (default " APP_PIXEL_ERROR_TEXT "; 0 = fixed "
          "rings of 2, 3 levels, and the fixed far terrain)", 0, 0, 0.0, 64.0 },
        { "radius", CORE_OPTION_INT, &o->radius, "R", "full-detail chunks of 32 m each way (default: from "
          "--pixel-error; with --radius or --levels the rings are fixed, radius 2)", 1, 32 },
        { "levels", CORE_OPTION_INT, &o->levels, "N", "rings of volumetric detail (default 3)", 1, 8 },
        { "simplify", CORE_OPTION_STRING, &o->simplify, "none|coarse|all", "which terrain chunks are simplified by "
          "their level's own error (default none; coarse: levels 1 and up; fewer triangles, more streaming work)" },
        { "grass", CORE_OPTION_STRING, &o->grass, "off|low|high", "grass patches (default low)" },
        { "water", CORE_OPTION_STRING, &o->water, "off|low|medium|high", "the sea and lakes (default low: blended, the frame never read back)" },
        { "rocks", CORE_OPTION_STRING, &o->rocks, "on|off", "rock piles (default on; the tile set is cached "
          "in out/rocks_tiles.bin when out/ exists)" },
        { "cliffs", CORE_OPTION_STRING, &o->cliffs, "on|off", "fractured blocks on steep bedrock walls (default on; their tiles are cached in out/ when it exists)" },
        { "detail", CORE_OPTION_STRING, &o->detail, "on|off", "the ground's 1 m detail layer and scale blend (default on)" },
        { "shadows", CORE_OPTION_STRING, &o->shadows, "off|low|high", "sun shadows (default low)" },
        { "memory", CORE_OPTION_INT, &o->memory_mb, "MB", "memory budget for terrain (default 384)", 16, 65536 },
        { "at", CORE_OPTION_STRING, &o->at, "X,Y,Z", "start with the eye here, metres (flying if it must)" },
        { "look", CORE_OPTION_STRING, &o->look, "YAW,PITCH", "start looking this way, degrees (yaw 0 = +z, "
          "90 = -x; pitch up, within ±89)" },
    };
    core_cli cli = { .program = "world", .summary = "walk an endless generated world",
                     .options = list, .option_count = CORE_COUNTOF(list) };
    o->seed = -1;
    o->pixel_error = APP_PIXEL_ERROR;
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    /* No --seed: the world folder's, else 1. */
    uint64_t saved_seed;
    if (o->seed < 0) o->seed = o->world && game_world_dir_seed(o->world, &saved_seed) == 1 ? (int)saved_seed : 1;
    desc->width = 1280;
    desc->height = 720;
    char error[512];
    if (o->size && !gfx_parse_size(o->size, &desc->width, &desc->height)) {
        snprintf(error, sizeof error, "'%s' is not WxH (16 to 16384 each)", o->size);
        return bad_value(&cli, "size", error);
    }
    if (o->grass && !grass_parse_quality(o->grass, &desc->grass)) {
        snprintf(error, sizeof error, "'%s' is not off, low or high", o->grass);
        return bad_value(&cli, "grass", error);
    }
    if (o->water && !terrain_water_parse_quality(o->water, &desc->water)) {
        snprintf(error, sizeof error, "'%s' is not off, low, medium or high", o->water);
        return bad_value(&cli, "water", error);
    }
    if (o->rocks && !rocks_parse_quality(o->rocks, &desc->rocks)) {
        snprintf(error, sizeof error, "'%s' is not on or off", o->rocks);
        return bad_value(&cli, "rocks", error);
    }
    if (o->cliffs && !rocks_parse_quality(o->cliffs, &desc->cliffs)) {
        snprintf(error, sizeof error, "'%s' is not on or off", o->cliffs);
        return bad_value(&cli, "cliffs", error);
    }
    struct stat out_dir;
    if (stat("out", &out_dir) == 0 && S_ISDIR(out_dir.st_mode)) {
        desc->rocks_cache_path = "out/rocks_tiles.bin";
        desc->cliffs_cache_dir = "out";
    }
    if (o->detail && strcmp(o->detail, "on") != 0 && strcmp(o->detail, "off") != 0) {
        snprintf(error, sizeof error, "'%s' is not on or off", o->detail);
        return bad_value(&cli, "detail", error);
    }
    desc->no_terrain_detail = o->detail && strcmp(o->detail, "off") == 0;
    if (o->shadows && !terrain_parse_shadow_quality(o->shadows, &desc->shadows)) {
        snprintf(error, sizeof error, "'%s' is not off, low or high", o->shadows);
        return bad_value(&cli, "shadows", error);
    }
    if (o->simplify && !terrain_parse_simplify(o->simplify, &desc->stream.simplify)) {
        snprintf(error, sizeof error, "'%s' is not none, coarse or all", o->simplify);
        return bad_value(&cli, "simplify", error);
    }
    /* The world's limits: ±1e9 m along the ground (walk.h's), ±1e5 m up and down. */
    static const char *const at_names[] = { "X", "Y", "Z" }, *const look_names[] = { "YAW", "PITCH" };
    static const double at_limits[] = { 1e9, 1e5, 1e9 }, look_limits[] = { INFINITY, 89 };
    desc->at_set = o->at != NULL;
    if (o->at && !parse_numbers(o->at, 3, "X,Y,Z", at_names, at_limits, desc->at, error, sizeof error))
        return bad_value(&cli, "at", error);
    desc->look_set = o->look != NULL;
    if (o->look && !parse_numbers(o->look, 2, "YAW,PITCH", look_names, look_limits, desc->look, error, sizeof error))
        return bad_value(&cli, "look", error);
    core_error walk_error = { 0 };
    if (o->walk && !game_walk_parse(o->walk, walk, &walk_error)) return bad_value(&cli, "walk", walk_error.message);
    if (o->tour && o->walk) {
        fprintf(stderr, "world: '--tour' and '--walk' cannot be used together\n");
        core_cli_print_usage(&cli, stderr);
        return 2;
    }
    if (o->tour && !game_walk_parse_text(game_walk_tour, strlen(game_walk_tour), "tour", walk, &walk_error)) {
        fprintf(stderr, "world: the built-in tour does not parse: %s\n", walk_error.message);   /* a programmer's error */
        return 1;
    }
    if (o->trace_frames && !o->common.trace_path) {
        fprintf(stderr, "world: '--trace-frames' needs '--trace FILE'\n");
        core_cli_print_usage(&cli, stderr);
        return 2;
    }
    if (o->record && o->replay) {
        fprintf(stderr, "world: '--record' and '--replay' cannot be used together\n");
        core_cli_print_usage(&cli, stderr);
        return 2;
    }
    return -1;
}

static void print_results(const game_app_stats_info *s, bool walked) {
    printf("world: %d frames after %d loading frames\n", s->frames, s->loading_frames);
    if (walked)
        printf("world: walked %.1f m (%.1f m from the start)%s, eye in solid on %d frames, waited %d frames\n",
               s->walked, s->from_start, s->walk_stuck ? ", stuck" : "", s->eye_in_solid_frames, s->waiting_frames);
    printf("world: cpu frame p50 %.2f ms, p99 %.2f ms, max %.2f ms, %d over 33 ms; without draw calls p50 %.2f ms, "
           "p99 %.2f ms\n", s->cpu_ms_p50, s->cpu_ms_p99, s->cpu_ms_max, s->hitches, s->engine_ms_p50, s->engine_ms_p99);
    printf("world: main thread's own CPU p50 %.2f ms, p99 %.2f ms (the driver's waits left out)\n", s->thread_ms_p50,
           s->thread_ms_p99);
    printf("world: %.0f triangles drawn a frame (median; the grass's, made on the GPU, not counted)\n", s->triangles_p50);
    printf("world: chunks %d wanted, %d ready, %d kept; %llu meshed, %llu empty, %llu cancelled, %llu evicted\n",
           s->stream.mesh_chunks_wanted, s->stream.mesh_chunks_ready, s->stream.mesh_chunks_kept,
           (unsigned long long)s->stream.chunks_meshed, (unsigned long long)s->stream.chunks_skipped_empty,
           (unsigned long long)s->stream.chunks_cancelled, (unsigned long long)s->stream.chunks_evicted);
    printf("world: terrain memory %.1f MB (peak %.1f MB), process peak %.1f MB\n",
           (double)s->stream.resident_bytes / 1048576.0, (double)s->stream.peak_resident_bytes / 1048576.0,
           (double)s->peak_rss_bytes / 1048576.0);
    if (s->strokes || s->edits.edits_applied || s->edited_chunks)
        printf("world: %llu tool strokes, %llu edits applied, %llu refused, %d chunks edited\n",
               (unsigned long long)s->strokes, (unsigned long long)s->edits.edits_applied,
               (unsigned long long)s->edits.edits_refused, s->edited_chunks);
    if (s->grass_tufts)
        printf("world: grass %llu tufts placed, %llu in the last frame's patches, %.3f ms a frame (max %.2f ms)\n",
               (unsigned long long)s->grass_tufts, (unsigned long long)s->grass_tufts_drawn, s->grass_ms_mean,
               s->grass_ms_max);
    if (s->rock_shapes)
        printf("world: rocks %llu placed, %llu drawn in the last frame; %u rock shapes in the tile set (%s)\n",
               (unsigned long long)s->rocks_placed, (unsigned long long)s->rocks_drawn, s->rock_shapes,
               s->rocks_build_seconds > 0 ? "built this run" : "from its cache");
    if (s->cliffs)
        printf("world: cliffs %llu blocks raised on steep bedrock walls in %llu fields (%.2f s of CPU, %.2f s of it "
               "for presence in %llu tile cells, reused %llu times); their tiles %s in %.2f s\n",
               (unsigned long long)s->cliff_blocks, (unsigned long long)s->cliff_fields, s->cliffs_amplify_seconds,
               s->cliffs_presence_seconds, (unsigned long long)s->cliff_cells_computed,
               (unsigned long long)s->cliff_cells_reused, s->cliff_tiles_from_cache ? "read from their cache" : "built",
               s->cliffs_build_seconds);
    printf("world: player at (%.4f, %.4f, %.4f), looking %.1f,%.1f\n", s->feet[0], s->feet[1], s->feet[2],
           s->look[0], s->look[1]);
}

int main(int argc, char **argv) {
    options o = { 0 };
    game_app_desc desc = { 0 };
    game_walk walk = { 0 };
    int rc = parse(argc, argv, &o, &desc, &walk);
    if (rc >= 0) return rc;
    trace_keep_frames(o.trace_frames);
    if (o.common.trace_path && !trace_start(o.common.trace_path)) return 2;
    trace_thread_name("main");
    desc.seed = (uint64_t)o.seed;
    desc.headless = o.headless;
    desc.threads = o.common.threads;
    desc.frames = o.frames;
    desc.walk = o.walk || o.tour ? &walk : NULL;
    desc.face_open_view = o.tour;
    /* The tour steps 1/30 s a frame: half the frames to draw for the same walk (llvmpipe draws
     * 640 × 360 at about 13 a second, so no one watching would see more), and the walker's and
     * the player's rules are in seconds (tested at 30, 60 and 144 Hz). */
    if (o.tour) desc.step_seconds = 1.0f / 30.0f;
    desc.no_head_bob = o.no_head_bob;
    desc.no_occlusion = o.no_ao;
    desc.record_path = o.record;
    desc.replay_path = o.replay;
    desc.bindings_path = o.bindings;
    desc.gamepad_mappings_path = o.gamepad_mappings;
    desc.screenshot_path = o.screenshot;
    desc.world_dir = o.world;
    desc.stream.half_width = o.radius;             /* .simplify was parsed with the flags */
    desc.stream.levels = o.levels;
    desc.stream.memory_budget = (size_t)o.memory_mb << 20;
    desc.pixel_error = (float)o.pixel_error;
    game_app *app = game_app_create(&desc);
    if (!app) {
        game_walk_free(&walk);
        return 1;
    }
    while (game_app_frame(app)) {}
    game_app_stats_info stats = game_app_stats(app);
    print_results(&stats, o.walk != NULL || o.tour);
    game_app_destroy(app);
    game_walk_free(&walk);
    trace_stop();
    return stats.eye_in_solid_frames > 0 ? 1 : 0;
}
