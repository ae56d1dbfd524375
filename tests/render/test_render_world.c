/* End to end: the walkable world (game/app.h) headless at a small size. A scripted walk over
 * generated terrain keeps the eye in the air and the terrain within its memory budget and shows
 * ground and sky; a recording replays to the same place; a walk 100 km out goes exactly as one
 * at the origin. */
#include "render_util.h"

#include "core/core.h"
#include "game/app.h"
#include "trace/trace.h"
#include "../rocks/rocks_test_cache.h"

#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <stb/stb_image.h>

#include "../engine/trace_file.h"

static const terrain_stream_desc small_view = { .half_width = 2, .levels = 2, .memory_budget = 64u << 20 };

/* A small rock tile set (one build a test run: rocks_test_cache.h). */
static rocks_tileset *small_rock_tiles(void) {
    rocks_tileset_desc desc = { .cells = 4, .voxels_per_cell = 5 };
    desc.cache_path = rocks_test_cache(&desc);
    return rocks_tileset_create(&desc);
}

/* Worlds here run without rocks unless a test gives a tile set: the default set takes the debug
 * build 40 s to make (test_render_rocks and test_rocks cover the rocks with small sets). Cliff
 * blocks only where a test asks for them (ROCKS_ON): under the sanitizers their tiles and their
 * presence tests more than double the tour's time (test_rocks covers them; tests/programs.sh
 * runs the release world, cliffs on). */
static game_app_stats_info run_world(game_app_desc desc) {
    if (!desc.rock_tiles) desc.rocks = ROCKS_OFF;
    if (desc.cliffs == ROCKS_DEFAULT) desc.cliffs = ROCKS_OFF;
    game_app *app = game_app_create(&desc);
    cr_assert(app, "the world did not start");
    int guard = 0;
    while (game_app_frame(app) && guard++ < 20000) {}
    game_app_stats_info stats = game_app_stats(app);
    game_app_destroy(app);
    return stats;
}

static game_walk parse_walk(const char *text) {
    game_walk walk;
    core_error error = { 0 };
    cr_assert(game_walk_parse_text(text, strlen(text), "test.walk", &walk, &error), "%s", error.message);
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
    game_app_stats_info s = run_world((game_app_desc){ .seed = 5, .width = 96, .height = 64, .headless = true,
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
 * frame N of the replay however long either took to load: the player ends where it did. Nothing
 * but the terrain is drawn, as in the walk 100 km out. */
Test(render_world, a_recorded_walk_replays_to_the_same_place, .timeout = 600) {
    game_walk walk = parse_walk("ahead\n0 25\n6 38 walk\n");
    char rec[] = "/tmp/world_rec_XXXXXX";
    int fd = mkstemp(rec);
    cr_assert(fd >= 0);
    close(fd);
    game_app_desc desc = { .seed = 9, .width = 64, .height = 48, .headless = true, .threads = 2, .walk = &walk,
                           .stream = small_view, .no_hud = true, .frames = 1500, .grass = GRASS_OFF,
                           .water = TERRAIN_WATER_OFF, .shadows = TERRAIN_SHADOWS_OFF };
    desc.record_path = rec;
    game_app_stats_info recorded = run_world(desc);
    desc.record_path = NULL;
    desc.replay_path = rec;
    desc.threads = 1;                           /* other scheduling, other loading time */
    game_app_stats_info replayed = run_world(desc);
    cr_expect_gt(recorded.frames, 60);
    cr_expect_eq(recorded.frames, replayed.frames);
    for (int a = 0; a < 3; a++)
        cr_expect_eq(recorded.feet[a], replayed.feet[a], "axis %d: %.6f recorded, %.6f replayed", a,
                     recorded.feet[a], replayed.feet[a]);
    remove(rec);
    game_walk_free(&walk);
}

/* Where the player ends is all this looks at: no grass, water or shadows to draw (the pictures
 * are other tests'), which halves its time under the sanitizers. */
Test(render_world, a_walk_a_hundred_kilometres_out_goes_as_at_the_origin, .timeout = 600) {
    game_walk walk = parse_walk("relative\n18 18\n-12 36 walk\n");
    game_app_stats_info at[2];
    for (int far = 0; far < 2; far++) {
        double offset = far ? 100800.0 : 0.0;
        at[far] = run_world((game_app_desc){ .width = 64, .height = 48, .headless = true, .threads = 2,
                                             .walk = &walk, .stream = small_view, .no_hud = true, .frames = 1500,
                                             .spawn = { offset + 8, offset + 8 }, .generate = render_rolling_chunk,
                                             .grass = GRASS_OFF, .water = TERRAIN_WATER_OFF,
                                             .shadows = TERRAIN_SHADOWS_OFF });
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
 * the hash of the chunk it changed; the app saves its edits as it closes. The saves are all these
 * runs look at: nothing but the terrain is drawn. */
static edited_run carve_and_close(const char *dir) {
    game_app *app = game_app_create(&(game_app_desc){ .seed = 3, .width = 96, .height = 64, .headless = true,
                                                      .threads = 2, .frames = 100000, .stream = small_view,
                                                      .no_clipmap = true, .world_dir = dir, .rocks = ROCKS_OFF,
                                                      .cliffs = ROCKS_OFF, .grass = GRASS_OFF,
                                                      .water = TERRAIN_WATER_OFF, .shadows = TERRAIN_SHADOWS_OFF });
    cr_assert(app);
    for (int guard = 0; !game_app_loaded(app) && guard < 20000; guard++) game_app_frame(app);
    game_app_stats_info s = game_app_stats(app);
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
    game_app_stats_info end = game_app_stats(app);
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
                                                      .no_clipmap = true, .world_dir = dir, .rocks = ROCKS_OFF,
                                                      .cliffs = ROCKS_OFF, .grass = GRASS_OFF,
                                                      .water = TERRAIN_WATER_OFF, .shadows = TERRAIN_SHADOWS_OFF });
    *started = app != NULL;
    if (!app) return 0;
    uint64_t hash = terrain_stacks_hash(terrain_world_stacks(game_app_world(app), chunk));
    game_app_stats_info s = game_app_stats(app);
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
    terrain_generation_desc params = terrain_generation_defaults(3);
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

/* ---- the tour (world --tour, what tools/play shows with no display) ---- */

/* Per quarter of a picture, the standard deviation of luminance (0…255) over blocks of 8 × 8
 * pixels (their means: the layout of the picture, not the grain of a texture, which a wall has
 * too once the ground is drawn with detail and normal maps); the share of the top eighth that is
 * sky-blue (blue above red by 20), and of the bottom quarter that is not the sky: farther than 40
 * (RGB distance) from the top eighth's mean colour (water is blue too). */
#define PICTURE_BLOCK 8

typedef struct picture_facts {
    double spread[4];                 /* top-left, top-right, bottom-left, bottom-right */
    double sky_top, ground_bottom;
} picture_facts;

static picture_facts picture_facts_of(const char *path) {
    int w, h, n;
    uint8_t *rgb = stbi_load(path, &w, &h, &n, 3);
    cr_assert(rgb, "no picture at %s", path);
    picture_facts f = { 0 };
    double sum[4] = { 0 }, sum2[4] = { 0 };
    int count[4] = { 0 }, top = 0, top_blue = 0, bottom = 0, bottom_ground = 0;
    double sky[3] = { 0 };
    for (int y = 0; y < h / 8; y++)
        for (int x = 0; x < w; x++)
            for (int c = 0; c < 3; c++) sky[c] += rgb[3 * (y * w + x) + c] / (double)(w * (h / 8));
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const uint8_t *p = rgb + 3 * (y * w + x);
            if (y < h / 8) top++, top_blue += p[2] > p[0] + 20;
            double far = hypot(hypot(p[0] - sky[0], p[1] - sky[1]), p[2] - sky[2]);
            if (y >= h - h / 4) bottom++, bottom_ground += far > 40.0;
        }
    for (int by = 0; by + PICTURE_BLOCK <= h; by += PICTURE_BLOCK)
        for (int bx = 0; bx + PICTURE_BLOCK <= w; bx += PICTURE_BLOCK) {
            double luma = 0;
            for (int y = by; y < by + PICTURE_BLOCK; y++)
                for (int x = bx; x < bx + PICTURE_BLOCK; x++) {
                    const uint8_t *p = rgb + 3 * (y * w + x);
                    luma += (0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2]) / (PICTURE_BLOCK * PICTURE_BLOCK);
                }
            int q = (by >= h / 2) * 2 + (bx >= w / 2);
            sum[q] += luma, sum2[q] += luma * luma, count[q]++;
        }
    for (int q = 0; q < 4; q++) {
        double mean = sum[q] / count[q];
        f.spread[q] = sqrt(fmax(sum2[q] / count[q] - mean * mean, 0.0));
    }
    f.sky_top = (double)top_blue / top;
    f.ground_bottom = (double)bottom_ground / bottom;
    stbi_image_free(rgb);
    return f;
}

/* The tour's threshold on spread: between a wall filling the frame (the test below measures it:
 * its quarters 3.8 to 5.5 on 8 × 8 blocks, where single pixels gave 6.1 to 7.7 once the rock
 * had detail and normal maps) and the least spread quarter of the tour's pictures (the grass
 * before the cave's mouth, 5.6 and 6.2 on seed 1 at 160 × 96 since the generator's octaves and
 * caves changed; 4.4 and 4.9 when the view stood 40 m back; the others 10.7 to 62). A regression
 * guard set from those measurements, with little margin at the cave. */
#define TOUR_MIN_SPREAD 5.0

/* Flat ground at y = 0, and from z = 4 on a cliff 60 m tall across the whole width. */
static void wall_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    (void)user, (void)x;
    terrain_stacks_builder_push(b, TERRAIN_BEDROCK, -TERRAIN_FLOOR_Y + (z >= 4 ? 60.0f : 0.0f));
}

static terrain_stacks *wall_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, wall_column, user);
}

/* The control for the threshold: standing 3.5 m from a cliff and facing it (walks keep yaw π,
 * +z), the picture is one surface, and at least one quarter falls under the threshold. */
Test(render_world, a_picture_of_a_wall_falls_under_the_tours_spread_threshold, .timeout = 300) {
    char shot[] = "/tmp/world_wall_XXXXXX.png";
    int fd = mkstemps(shot, 4);
    cr_assert(fd >= 0);
    close(fd);
    game_walk walk = parse_walk("ahead\n0 0.5\n");
    run_world((game_app_desc){ .seed = 1, .width = 160, .height = 96, .headless = true, .threads = 2,
                               .walk = &walk, .stream = small_view, .no_hud = true, .no_clipmap = true,
                               .generate = wall_chunk, .screenshot_path = shot, .spawn = { 0.5, 0.5 } });
    picture_facts f = picture_facts_of(shot);
    double lowest = fmin(fmin(f.spread[0], f.spread[1]), fmin(f.spread[2], f.spread[3]));
    cr_log_info("wall: spread %.1f %.1f %.1f %.1f", f.spread[0], f.spread[1], f.spread[2], f.spread[3]);
    cr_expect_lt(lowest, TOUR_MIN_SPREAD, "the wall's quarters spread %.1f at the least", lowest);
    game_walk_free(&walk);
    unlink(shot);
}

Test(render_world, the_tour_ends_where_its_script_says_and_every_picture_shows_sky_over_land, .timeout = 600) {
    char dir[] = "/tmp/world_tour_XXXXXX", sheet[64], path[80];
    cr_assert(mkdtemp(dir));
    snprintf(sheet, sizeof sheet, "%s/tour.png", dir);
    game_walk walk = parse_walk(game_walk_tour);
    /* a small tile set: the rocks stop shows rocks, as tools/play's does, at a debug build's cost */
    rocks_tileset *tiles = small_rock_tiles();
    cr_assert_not_null(tiles);
    game_app_stats_info s = run_world((game_app_desc){ .seed = 1, .width = 160, .height = 96, .headless = true,
                                                  .threads = 2, .walk = &walk, .face_open_view = true,
                                                  .stream = small_view, .screenshot_path = sheet,
                                                  .rock_tiles = tiles });
    cr_expect_gt(s.rocks_placed, 20, "the tour ends with %llu rocks placed", (unsigned long long)s.rocks_placed);
    cr_expect(s.walk_done && !s.walk_stuck, "the tour %s after %.1f m", s.walk_stuck ? "got stuck" : "did not end",
              s.walked);
    cr_expect_eq(s.eye_in_solid_frames, 0);
    /* Seed 1 has a cave mouth within 150 m of the tour's second stop (walk_cave.c finds it), a
     * shore within 150 m of the cave's view (walk_shore.c) and a pile of rocks within 150 m of the
     * shore's view (walk_rocks.c): six pictures, the third looking into the cave, the fourth out
     * over the water, the fifth down at the rocks. That one looks down 30° or so with a 60° field,
     * so its top edge is near the horizon and it promises no sky (and the land-below test, which
     * compares the bottom with the top's sky, means nothing there); every picture has no quarter
     * that is one surface. */
    for (int n = 1; n <= 6; n++) {
        snprintf(path, sizeof path, "%s/tour-%d.png", dir, n);
        picture_facts f = picture_facts_of(path);
        if (n != 5) {
            cr_expect_geq(f.sky_top, 0.5, "picture %d: sky over %.0f %% of the top eighth", n, 100 * f.sky_top);
            cr_expect_geq(f.ground_bottom, 0.5, "picture %d: land or water below, %.0f %% of the bottom quarter not sky",
                          n, 100 * f.ground_bottom);
        }
        for (int q = 0; q < 4; q++)
            cr_expect_geq(f.spread[q], TOUR_MIN_SPREAD, "picture %d, quarter %d: spread %.1f (one surface?)", n, q,
                          f.spread[q]);
        cr_log_info("picture %d: spread %.1f %.1f %.1f %.1f, sky %.2f, ground %.2f", n, f.spread[0], f.spread[1],
                    f.spread[2], f.spread[3], f.sky_top, f.ground_bottom);
    }
    snprintf(path, sizeof path, "%s/tour-7.png", dir);
    cr_expect(access(path, F_OK) != 0, "a seventh picture");
    /* The contact sheet: the six at half size (80 × 48), three columns, two rows, full. */
    int w, h, c;
    uint8_t *rgb = stbi_load(sheet, &w, &h, &c, 3);
    cr_assert(rgb, "no contact sheet");
    cr_expect(w == 240 && h == 96, "%d x %d", w, h);
    if (w == 240 && h == 96) {
        /* Where five pictures left the sheet's own colour (app_write_contact_sheet: 24, 26, 30) at
         * the second row's ends, the fourth and sixth pictures are. */
        const uint8_t *left = rgb + ((size_t)72 * 240 + 20) * 3, *right = rgb + ((size_t)72 * 240 + 220) * 3;
        cr_expect(!(left[0] == 24 && left[1] == 26 && left[2] == 30), "left end is the background");
        cr_expect(!(right[0] == 24 && right[1] == 26 && right[2] == 30), "right end is the background");
    }
    stbi_image_free(rgb);
    game_walk_free(&walk);
    rocks_tileset_destroy(tiles);
    char command[64];
    snprintf(command, sizeof command, "rm -rf '%s'", dir);
    cr_expect_eq(system(command), 0);
}

/* ---- a view asked for (world --at X,Y,Z --look YAW,PITCH) ---- */

static game_app_stats_info run_at(double x, double y, double z, double yaw, double pitch, const game_walk *walk) {
    return run_world((game_app_desc){ .width = 64, .height = 48, .headless = true, .threads = 2, .walk = walk,
                                      .frames = walk ? 2000 : 5, .stream = small_view, .no_clipmap = true,
                                      .generate = wall_chunk, .at_set = true, .at = { x, y, z }, .look_set = true,
                                      .look = { yaw, pitch } });
}

/* In the wall's world (flat ground at y = 0, solid up to 60 m from z = 4 on), five frames past
 * loading: the eye is where it was put and the view turned as asked, flying where standing would
 * have moved it. terrain_view looks along (sin yaw·cos pitch, sin pitch, −cos yaw·cos pitch);
 * --look's yaw 0 is +z, 90 turns right to −x, 180 is −z, 270 is +x. */
Test(render_world, a_view_asked_for_is_drawn_exactly_as_asked, .timeout = 600) {
    const double d = 3.14159265358979323846 / 180.0;
    struct {
        double at[3], look[2];
        bool flying;
        double forward[3];
    } cases[] = {
        { { 0.5, 30, -20.5 }, { 90, -20 }, true, { -cos(20 * d), -sin(20 * d), 0 } },    /* over a drop */
        { { 0.5, 30, 20.5 }, { 180, 0 }, true, { 0, 0, -1 } },                          /* inside the cliff */
        { { 0.5, 1.82, -20.5 }, { 270, 89 }, false, { cos(89 * d), sin(89 * d), 0 } },   /* feet 0.2 m up */
    };
    for (size_t n = 0; n < sizeof cases / sizeof cases[0]; n++) {
        game_app_stats_info s = run_at(cases[n].at[0], cases[n].at[1], cases[n].at[2], cases[n].look[0], cases[n].look[1],
                                  NULL);
        cr_expect_eq(s.frames, 5);
        cr_expect_eq(s.flying, cases[n].flying, "case %zu: flying %d", n, s.flying);
        cr_expect_eq(s.eye_in_solid_frames, 0, "case %zu: a held eye is not the controller's", n);
        double forward[3] = { sin(s.yaw) * cos(s.pitch), sin(s.pitch), -cos(s.yaw) * cos(s.pitch) };
        for (int a = 0; a < 3; a++) {
            cr_expect(fabs(s.eye[a] - cases[n].at[a]) < 1e-6, "case %zu, axis %d: eye %.9f, asked %.9f", n, a,
                      s.eye[a], cases[n].at[a]);
            cr_expect(fabs(forward[a] - cases[n].forward[a]) < 1e-6, "case %zu, axis %d: forward %.9f, wanted %.9f",
                      n, a, forward[a], cases[n].forward[a]);
        }
        cr_expect(fabs(s.feet[1] - (cases[n].at[1] - 1.62)) < 1e-6, "case %zu: feet at %.9f", n, s.feet[1]);
        for (int a = 0; a < 2; a++)
            cr_expect(fabs(s.look[a] - cases[n].look[a]) < 1e-3, "case %zu: look %.6f, asked %.6f", n, s.look[a],
                      cases[n].look[a]);
    }
}

/* A walk from a view asked for starts there and heads the way it looks: `ahead` 10 m from the
 * flat ground facing +x (yaw 270) ends 10 m along +x, on the ground. */
Test(render_world, a_walk_starts_from_the_view_asked_for, .timeout = 600) {
    game_walk walk = parse_walk("ahead\n0 10 walk\n");
    game_app_stats_info s = run_at(0.5, 1.62, -20.5, 270, 0, &walk);
    cr_expect(s.walk_done && !s.walk_stuck, "the walk %s", s.walk_stuck ? "got stuck" : "did not end");
    cr_expect_eq(s.eye_in_solid_frames, 0);
    cr_expect(hypot(s.feet[0] - 10.5, s.feet[2] + 20.5) <= 2.0 + 1e-6, "ended at (%.2f, %.2f)", s.feet[0], s.feet[2]);
    cr_expect(fabs(s.feet[1]) < 0.05, "feet at %.3f over flat ground at 0", s.feet[1]);
    game_walk_free(&walk);
}

/* Rocks in the game: seed 1 has talus at the foot of a wall near (49.5, 17.5) (its generator's
 * rock layers); a world started looking at it places rocks there and draws them, and the player
 * standing on the pile is never inside a rock. */
Test(render_world, the_game_places_and_draws_the_generated_talus) {
    rocks_tileset *tiles = small_rock_tiles();
    cr_assert_not_null(tiles);
    game_app_stats_info s = run_world((game_app_desc){ .seed = 1, .width = 96, .height = 64, .headless = true,
                                                  .threads = 2, .frames = 30, .stream = small_view,
                                                  .no_clipmap = true, .rock_tiles = tiles, .at_set = true,
                                                  .at = { 49.5, 27, 6 }, .look_set = true, .look = { 0, -25 } });
    cr_expect_gt(s.rocks_placed, 100, "%llu rocks placed around the talus", (unsigned long long)s.rocks_placed);
    cr_expect_gt(s.rocks_drawn, 20, "%llu rocks drawn looking at it", (unsigned long long)s.rocks_drawn);
    cr_expect_eq(s.rock_shapes, tiles->rock_count);
    rocks_tileset_destroy(tiles);
}

/* ---- the frame as ECS systems (app.h) ---- */

/* The fixed step (GAME_PLAYER_STEP) makes where a walk ends independent of the frame rate: the
 * walker and the body see the same steps at 30, 60 and 144 frames a second; only how many
 * frames they span differs. Synthetic rolling ground, nothing drawn but the terrain. */
Test(render_world, a_walk_ends_at_the_same_place_at_30_60_and_144_frames_a_second, .timeout = 600) {
    game_walk walk = parse_walk("relative\n6 5\n-3 9 walk\n");
    const float rates[3] = { 30.0f, 60.0f, 144.0f };
    game_app_stats_info at[3];
    for (int r = 0; r < 3; r++) {
        at[r] = run_world((game_app_desc){ .width = 48, .height = 32, .headless = true, .threads = 2, .walk = &walk,
                                           .stream = small_view, .no_hud = true, .frames = 20000, .spawn = { 8, 8 },
                                           .generate = render_rolling_chunk, .step_seconds = 1.0f / rates[r],
                                           .no_clipmap = true, .grass = GRASS_OFF, .water = TERRAIN_WATER_OFF,
                                           .shadows = TERRAIN_SHADOWS_OFF });
        cr_expect(at[r].walk_done, "%.0f fps: the walk did not end", (double)rates[r]);
    }
    /* More frames at a higher rate, in proportion (loading frames aside). */
    cr_expect_gt(at[2].frames, 4 * at[0].frames, "%d frames at 144/s, %d at 30/s", at[2].frames, at[0].frames);
    for (int r = 1; r < 3; r++)
        for (int a = 0; a < 3; a++)
            cr_expect_eq(at[r].feet[a], at[0].feet[a], "axis %d: %.9f at %.0f fps, %.9f at 30 fps", a, at[r].feet[a],
                         (double)rates[r], at[0].feet[a]);
    game_walk_free(&walk);
}

/* The systems each phase zone holds on the main thread, as a trace of the world shows them. */
static bool zone_inside(const core_json_value *events, const char *zone, const char *phase) {
    enum { DEPTH = 64 };
    const char *stack[DEPTH];
    int depth = 0;
    double main_tid = -1;
    for (size_t i = 0; i < events->array.count; i++) {
        const core_json_value *e = &events->array.items[i];
        const core_json_value *ph = core_json_get(e, "ph"), *name = core_json_get(e, "name");
        if (!ph || ph->type != CORE_JSON_STRING) continue;
        double tid = core_json_number_or(core_json_get(e, "tid"), -1);
        if (ph->string.chars[0] == 'E') {              /* ends carry no name */
            if (tid == main_tid && depth > 0) depth--;
            continue;
        }
        if (!name || name->type != CORE_JSON_STRING) continue;
        if (ph->string.chars[0] == 'B' && strcmp(name->string.chars, "input") == 0 && main_tid < 0) main_tid = tid;   /* ecs_progress's thread */
        if (tid != main_tid) continue;
        if (ph->string.chars[0] == 'B') {
            if (strcmp(name->string.chars, zone) == 0)
                for (int d = 0; d < depth && d < DEPTH; d++)
                    if (strcmp(stack[d], phase) == 0) return true;
            if (depth < DEPTH) stack[depth] = name->string.chars;
            depth++;
        }
    }
    return false;
}

Test(render_world, the_frame_goes_through_the_input_game_draw_and_present_phases_as_systems, .timeout = 300) {
    char path[] = "/tmp/world_phases_XXXXXX.json";
    int fd = mkstemps(path, 5);
    cr_assert(fd >= 0);
    close(fd);
    cr_assert(trace_start(path));
    /* Synthetic ground starts at once; the clipmap is kept for its lod-phase system. */
    run_world((game_app_desc){ .width = 48, .height = 32, .headless = true, .threads = 2, .frames = 4,
                               .stream = small_view, .generate = render_rolling_chunk, .spawn = { 8, 8 },
                               .grass = GRASS_OFF, .water = TERRAIN_WATER_OFF, .shadows = TERRAIN_SHADOWS_OFF });
    trace_stop();
    core_arena arena = { 0 };
    const core_json_value *events = trace_file_load(path, &arena, NULL);
    static const char *const expected[][2] = {
        { "input", "input" }, { "player", "game" }, { "camera", "game" }, { "tools", "game" },
        { "terrain_draw", "draw" }, { "sky", "draw" }, { "hud", "draw" }, { "screenshot", "present" },
        { "terrain_stream", "stream" }, { "terrain_clipmap", "lod" }, { "terrain_upload", "draw" },
        { "terrain_stream_submit", "background" },
    };
    for (size_t i = 0; i < sizeof expected / sizeof expected[0]; i++)
        cr_expect(zone_inside(events, expected[i][0], expected[i][1]), "no '%s' zone inside a '%s' phase zone",
                  expected[i][0], expected[i][1]);
    cr_expect(!zone_inside(events, "player", "draw"), "the player system inside the draw phase");
    core_arena_release(&arena);
}
