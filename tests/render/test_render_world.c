/* End to end: the walkable world (game/app.h) headless at a small size. A scripted walk over
 * generated terrain keeps the eye in the air and the terrain within its memory budget and shows
 * ground and sky; a recording replays to the same place; a walk 100 km out goes exactly as one
 * at the origin. */
#include "render_util.h"

#include "core/core.h"
#include "game/app.h"

#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <stb/stb_image.h>

static const terrain_stream_desc small_view = { .half_width = 2, .levels = 2, .memory_budget = 64u << 20 };

static game_app_stats run_world(game_app_desc desc) {
    game_app *app = game_app_create(&desc);
    cr_assert(app, "the world did not start");
    int guard = 0;
    while (game_app_frame(app) && guard++ < 20000) {}
    game_app_stats stats = game_app_stats_get(app);
    game_app_destroy(app);
    return stats;
}

static game_walk parse_walk(const char *text) {
    game_walk walk;
    char error[256];
    cr_assert(game_walk_parse_text(text, strlen(text), "test.walk", &walk, error, sizeof error), "%s", error);
    return walk;
}

/* Distinct colours, and how many of the top rows are sky-blue (blue above red) and of the bottom
 * rows are not. */
static void screenshot_facts(const char *path, int *colours, double *sky_top, double *ground_bottom) {
    int w, h, n;
    uint8_t *rgb = stbi_load(path, &w, &h, &n, 3);
    cr_assert(rgb, "no screenshot at %s", path);
    int seen = 0;
    uint32_t *list = malloc((size_t)w * (size_t)h * sizeof *list);
    int top = 0, top_blue = 0, bottom = 0, bottom_ground = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const uint8_t *p = rgb + 3 * (y * w + x);
            uint32_t c = (uint32_t)p[0] << 16 | (uint32_t)p[1] << 8 | p[2];
            int k = 0;
            while (k < seen && list[k] != c) k++;
            if (k == seen && seen < 4096) list[seen++] = c;
            bool blue = p[2] > p[0] + 20;
            if (y < h / 8) top++, top_blue += blue;
            if (y >= h - h / 4) bottom++, bottom_ground += !blue;
        }
    *colours = seen;
    *sky_top = (double)top_blue / top;
    *ground_bottom = (double)bottom_ground / bottom;
    free(list);
    stbi_image_free(rgb);
}

Test(render_world, a_scripted_walk_stays_above_ground_within_budget_and_shows_ground_and_sky, .timeout = 600) {
    game_walk walk = parse_walk("ahead\n0 120\n");
    char shot[] = "/tmp/world_walk_XXXXXX.png";
    int fd = mkstemps(shot, 4);
    cr_assert(fd >= 0);
    close(fd);
    game_app_stats s = run_world((game_app_desc){ .seed = 5, .width = 96, .height = 64, .headless = true,
                                                  .threads = 2, .walk = &walk, .stream = small_view,
                                                  .screenshot_path = shot, .frames = 2000 });
    cr_expect_gt(s.frames, 200, "only %d frames", s.frames);
    cr_expect_eq(s.eye_in_solid_frames, 0, "the eye was in the ground on %d frames", s.eye_in_solid_frames);
    cr_expect_geq(s.from_start, 100.0, "walked only %.1f m from the start", s.from_start);
    cr_expect_leq(s.stream.peak_resident_bytes, small_view.memory_budget, "%.1f MB resident",
                  (double)s.stream.peak_resident_bytes / 1048576.0);
    cr_expect_gt(s.stream.chunks_meshed, 0);
    int colours;
    double sky, ground;
    screenshot_facts(shot, &colours, &sky, &ground);
    cr_expect_gt(colours, 50, "the screenshot has %d colours", colours);
    cr_expect_gt(sky, 0.5, "%.0f%% of the top rows are sky", 100 * sky);
    cr_expect_gt(ground, 0.5, "%.0f%% of the bottom rows are ground", 100 * ground);
    remove(shot);
    game_walk_free(&walk);
}

/* Recording and replaying go through the same loading wait, so frame N of the recording is
 * frame N of the replay however long either took to load: the player ends where it did. */
Test(render_world, a_recorded_walk_replays_to_the_same_place, .timeout = 600) {
    game_walk walk = parse_walk("ahead\n0 40\n10 60 walk\n");
    char rec[] = "/tmp/world_rec_XXXXXX";
    int fd = mkstemp(rec);
    cr_assert(fd >= 0);
    close(fd);
    game_app_desc desc = { .seed = 9, .width = 64, .height = 48, .headless = true, .threads = 2, .walk = &walk,
                           .stream = small_view, .no_hud = true, .frames = 1500 };
    desc.record_path = rec;
    game_app_stats recorded = run_world(desc);
    desc.record_path = NULL;
    desc.replay_path = rec;
    desc.threads = 1;                           /* other scheduling, other loading time */
    game_app_stats replayed = run_world(desc);
    cr_expect_gt(recorded.frames, 60);
    cr_expect_eq(recorded.frames, replayed.frames);
    for (int a = 0; a < 3; a++)
        cr_expect_eq(recorded.feet[a], replayed.feet[a], "axis %d: %.6f recorded, %.6f replayed", a,
                     recorded.feet[a], replayed.feet[a]);
    remove(rec);
    game_walk_free(&walk);
}

Test(render_world, a_walk_a_hundred_kilometres_out_goes_as_at_the_origin, .timeout = 600) {
    game_walk walk = parse_walk("relative\n30 30\n-20 60 walk\n");
    game_app_stats at[2];
    for (int far = 0; far < 2; far++) {
        double offset = far ? 100800.0 : 0.0;
        at[far] = run_world((game_app_desc){ .width = 64, .height = 48, .headless = true, .threads = 2,
                                             .walk = &walk, .stream = small_view, .no_hud = true, .frames = 1500,
                                             .spawn = { offset + 8, offset + 8 }, .generate = render_rolling_chunk });
        at[far].feet[0] -= offset;
        at[far].feet[2] -= offset;
        cr_expect_eq(at[far].eye_in_solid_frames, 0);
    }
    cr_expect_eq(at[0].frames, at[1].frames, "%d frames at the origin, %d 100 km out", at[0].frames, at[1].frames);
    /* Positions there are ~1e5 m, doubles keep ~1e-11 m; the controller works relative to a
     * local origin, so the two walks may differ only in the last bits of the offset. */
    for (int a = 0; a < 3; a++)
        cr_expect(fabs(at[0].feet[a] - at[1].feet[a]) < 1e-6, "axis %d: %.9f at the origin, %.9f out there", a,
                  at[0].feet[a], at[1].feet[a]);
    game_walk_free(&walk);
}

/* ---- edits that last (--world DIR) ---- */

typedef struct edited_run {
    terrain_chunk_coord chunk;
    uint64_t hash;                    /* the chunk after the edit settled */
    double feet[3];                   /* where the player stood at the end */
} edited_run;

/* Loads the world, carves a ball where the ground is under the spawn, lets it settle and returns
 * the hash of the chunk it changed; the app saves its edits as it closes. */
static edited_run carve_and_close(const char *dir) {
    game_app *app = game_app_create(&(game_app_desc){ .seed = 3, .width = 96, .height = 64, .headless = true,
                                                      .threads = 2, .frames = 100000, .stream = small_view,
                                                      .no_clipmap = true, .world_dir = dir });
    cr_assert(app);
    for (int guard = 0; !game_app_loaded(app) && guard < 20000; guard++) game_app_frame(app);
    game_app_stats s = game_app_stats_get(app);
    double origin[3] = { s.feet[0] + 3.5, s.feet[1] + 4, s.feet[2] + 3.5 };
    terrain_ray_hit hit;
    cr_assert(terrain_raycast(game_app_world(app), origin, (const float[3]){ 0, -1, 0 }, 40, &hit));
    cr_assert(terrain_ecs_edit(game_app_terrain(app), &(terrain_edit){ .tool = TERRAIN_EDIT_SCULPT_CARVE,
        .sculpt = { .target = { hit.position[0], hit.position[1], hit.position[2] }, .radius = 3 } }));
    for (int frame = 0; frame < 5; frame++) game_app_frame(app);
    cr_assert_eq(terrain_ecs_edit_stats(game_app_terrain(app)).edits_applied, 1);
    double chunk = TERRAIN_CHUNK_COLUMNS * TERRAIN_COLUMN_SIZE;
    edited_run run = { .chunk = { (int64_t)floor(hit.position[0] / chunk), (int64_t)floor(hit.position[2] / chunk) } };
    run.hash = terrain_stacks_hash(terrain_world_stacks(game_app_world(app), run.chunk));
    game_app_stats end = game_app_stats_get(app);
    memcpy(run.feet, end.feet, sizeof run.feet);
    game_app_destroy(app);
    return run;
}

/* The chunk's hash in a run of the folder; *started false when the run was refused. `feet`
 * (may be NULL) gets where the player stands as the run starts. */
static uint64_t chunk_hash_in(const char *dir, uint64_t seed, terrain_chunk_coord chunk, bool *started,
                              double *feet) {
    game_app *app = game_app_create(&(game_app_desc){ .seed = seed, .width = 96, .height = 64, .headless = true,
                                                      .threads = 2, .frames = 1, .stream = small_view,
                                                      .no_clipmap = true, .world_dir = dir });
    *started = app != NULL;
    if (!app) return 0;
    uint64_t hash = terrain_stacks_hash(terrain_world_stacks(game_app_world(app), chunk));
    game_app_stats s = game_app_stats_get(app);
    if (feet) memcpy(feet, s.feet, sizeof s.feet);
    game_app_destroy(app);
    return hash;
}

/* A carve saved in the world folder is there in the next run, byte for byte, and the player
 * stands where the last run ended; another seed is refused; a damaged database is reported and
 * set aside, and the world comes back as generated. */
Test(render_world, edits_are_saved_and_come_back_and_a_damaged_file_is_set_aside) {
    char dir[] = "/tmp/world_edits_XXXXXX";
    cr_assert(mkdtemp(dir));
    edited_run run = carve_and_close(dir);
    terrain_generation_params params = terrain_generation_defaults(3);
    terrain_stacks *fresh = terrain_generate_chunk(&params, run.chunk);
    uint64_t generated = terrain_stacks_hash(fresh);
    terrain_stacks_destroy(fresh);
    cr_assert_neq(run.hash, generated, "the carve changed the chunk");
    bool started;
    double feet[3];
    cr_expect_eq(chunk_hash_in(dir, 3, run.chunk, &started, feet), run.hash, "the next run has the edit");
    cr_assert(started);
    for (int a = 0; a < 3; a++)
        cr_expect(fabs(feet[a] - run.feet[a]) < 1e-9, "axis %d: the run starts at %.6f, the last ended at %.6f", a,
                  feet[a], run.feet[a]);
    chunk_hash_in(dir, 4, run.chunk, &started, NULL);
    cr_expect(!started, "a folder of seed 3 refuses seed 4");
    /* 64 bytes of the database's second page overwritten (a table's root page). */
    char path[512];
    snprintf(path, sizeof path, "%s/world.db", dir);
    FILE *f = fopen(path, "r+b");
    cr_assert(f, "no database %s", path);
    fseek(f, 4096, SEEK_SET);
    for (int b = 0; b < 64; b++) fputc(0xa5, f);
    fclose(f);
    cr_expect_eq(chunk_hash_in(dir, 3, run.chunk, &started, NULL), generated, "a damaged world comes back as generated");
    cr_expect(started, "a damaged database never stops the game");
    char bad[520];
    snprintf(bad, sizeof bad, "%s.bad", path);
    cr_expect_eq(access(bad, F_OK), 0, "set aside as %s", bad);
    char command[600];
    snprintf(command, sizeof command, "rm -rf '%s'", dir);
    cr_expect_eq(system(command), 0);
}
