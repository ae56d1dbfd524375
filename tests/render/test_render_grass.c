/* Grass patches (modules/vegetation): where tufts grow, that they land in the same place every
 * run and on every thread count, and that an edit re-places them in the frame it is drawn.
 * Worlds are made by hand, so the expected counts follow from the lattice: on flat soil every
 * cell of the lattice (density² a square metre) holds exactly one tuft. */
#include "render_util.h"

#include "core/core.h"
#include "ecs/ecs.h"
#include "jobs/jobs.h"
#include "terrain/terrain.h"
#include "vegetation/vegetation.h"

#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DT (1.0f / 60.0f)
#define WIDTH 160
#define HEIGHT 90

typedef enum ground_kind { GROUND_FLAT, GROUND_SLOPE_60, GROUND_UNDER_WATER, GROUND_CAVE, GROUND_SAND, GROUND_ROCKS } ground_kind;

/* Flat soil at 10 m; a 60° slope (tan 60° metres up per metre along x); a sea bed 5 m under
 * sea level 0; a cave: floor at 10 m under a roof from 14 to 20 m; sand or rocks over soil. */
static void ground_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    (void)z;
    ground_kind kind = *(const ground_kind *)user;
    float floor_to = -TERRAIN_FLOOR_Y;             /* from the floor to y = 0 */
    switch (kind) {
    case GROUND_FLAT: terrain_stacks_builder_push(b, TERRAIN_BEDROCK, floor_to + 10); break;
    case GROUND_SLOPE_60:
        terrain_stacks_builder_push(b, TERRAIN_BEDROCK, floor_to + 40 + 1.7320508f * (float)x);
        break;
    case GROUND_UNDER_WATER:
        terrain_stacks_builder_push(b, TERRAIN_BEDROCK, floor_to - 5);
        terrain_stacks_builder_push(b, TERRAIN_WATER, 5);
        break;
    case GROUND_CAVE:
        terrain_stacks_builder_push(b, TERRAIN_BEDROCK, floor_to + 10);
        terrain_stacks_builder_push(b, TERRAIN_AIR, 4);
        terrain_stacks_builder_push(b, TERRAIN_BEDROCK, 6);
        break;
    case GROUND_SAND:
    case GROUND_ROCKS:
        terrain_stacks_builder_push(b, TERRAIN_BEDROCK, floor_to + 6);
        terrain_stacks_builder_push(b, kind == GROUND_SAND ? TERRAIN_SAND : TERRAIN_ROCKS, 4);
        break;
    }
}

static terrain_stacks *ground_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, ground_column, user);
}

typedef struct meadow {
    ground_kind kind;
    gfx_context *gfx;
    job_system *jobs;
    ecs_world *ecs;
    terrain_world *world;
    terrain_ecs *te;
    terrain_renderer *renderer;
    grass_system *grass;
    terrain_view view;
} meadow;

/* 3 × 3 level-0 chunks around chunk (0, 0), mesh layers y_first … y_last, and grass of the
 * given density (lattice cells per metre). */
static void meadow_open(meadow *m, ground_kind kind, int threads, int density, int64_t y_first, int64_t y_last) {
    memset(m, 0, sizeof *m);
    m->kind = kind;
    m->gfx = render_offscreen(WIDTH, HEIGHT);
    cr_assert_not_null(m->gfx);
    m->jobs = job_system_create(&(job_system_desc){ .threads = threads });
    m->ecs = ecs_world_create(&(ecs_world_desc){ .jobs = m->jobs });
    terrain_generation_desc generation = terrain_generation_defaults(5);
    generation.sea_level = 0;
    m->world = terrain_world_create(&(terrain_world_desc){ .generation = generation, .generate = ground_chunk,
                                                           .generate_user = &m->kind });
    m->te = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = m->ecs, .terrain = m->world });
    m->renderer = terrain_renderer_create(m->gfx, &(terrain_renderer_desc){ .sea_level = 0 });
    cr_assert_not_null(m->renderer);
    m->grass = grass_system_create(&(grass_system_desc){ .gfx = m->gfx, .ecs = m->ecs, .world = m->world,
                                           .quality = GRASS_HIGH, .density = density, .max_placements = 16 });
    cr_assert_not_null(m->grass);
    terrain_ecs_spawn_area(m->te, 0, 0, 1, y_first, y_last);
    m->view = (terrain_view){ .camera = { 16, 11.7, 4 }, .yaw = 3.14159265f, .pitch = -0.35f,
                              .aspect = (float)WIDTH / HEIGHT };
}

static void meadow_close(meadow *m) {
    grass_system_destroy(m->grass);
    terrain_ecs_destroy(m->te);
    terrain_renderer_destroy(m->renderer);
    ecs_world_destroy(m->ecs);
    terrain_world_destroy(m->world);
    job_system_destroy(m->jobs);
    gfx_context_destroy(m->gfx);
}

/* One frame as the game draws it; grass off draws the same frame without the grass. */
static void meadow_frame(meadow *m, bool draw_grass) {
    gfx_frame_begin(m->gfx);
    grass_set_view(m->grass, &m->view, NULL);
    terrain_ecs_set_view(m->te, &m->view);
    ecs_progress(m->ecs, DT);
    terrain_ecs_draw(m->te, m->renderer, &m->view);
    if (draw_grass) grass_draw(m->grass, &m->view);
    gfx_frame_end(m->gfx);
}

static render_image meadow_image(meadow *m) {
    render_image image = { WIDTH, HEIGHT, core_alloc(WIDTH * HEIGHT * 4) };
    gfx_read_pixels(m->gfx, image.rgba);
    return image;
}

typedef struct tuft { float x, y, z; } tuft;

/* Every placed tuft's root in world metres (read back from the patches' buffers). */
static tuft *meadow_tufts(meadow *m, size_t *count) {
    ecs_component patch_c = ecs_component_lookup(m->ecs, "GrassPatch");
    ecs_query *q = ecs_query_create(m->ecs, &(ecs_query_desc){ .with = { patch_c } });
    size_t total = 0, capacity = 0;
    tuft *tufts = NULL;
    ecs_iter it = ecs_query_iter(m->ecs, q);
    while (ecs_query_next(&it)) {
        GrassPatch *patches = ecs_field(&it, 0);
        for (int i = 0; i < it.count; i++) {
            const GrassPatch *p = &patches[i];
            if (!p->tufts) continue;
            float *data = core_alloc((size_t)p->tufts * 32);
            glGetNamedBufferSubData(gfx_buffer_gl(p->tuft_buffer), 0, (GLsizeiptr)p->tufts * 32, data);
            tufts = core_grow(tufts, &capacity, total + p->tufts, sizeof *tufts);
            for (uint32_t t = 0; t < p->tufts; t++)
                tufts[total++] = (tuft){ (float)(p->origin[0] + data[8 * t]), (float)(p->origin[1] + data[8 * t + 1]),
                                         (float)(p->origin[2] + data[8 * t + 2]) };
            core_free(data, (size_t)p->tufts * 32);
        }
    }
    ecs_query_destroy(m->ecs, q);
    *count = total;
    return tufts;
}

/* On flat soil every lattice cell holds one tuft: 9 chunks of 32 × 32 m at 2 cells a metre each
 * way are 9 · 64² = 36 864 tufts, all at the ground's height, and none outside the chunks. */
Test(render_grass, flat_soil_holds_one_tuft_per_lattice_cell) {
    meadow m;
    meadow_open(&m, GROUND_FLAT, 2, 2, 0, 0);
    for (int frame = 0; frame < 4; frame++) meadow_frame(&m, true);
    grass_system_stats_info st = grass_system_stats(m.grass);
    cr_expect_eq(st.patches, 9);
    cr_expect_eq(st.tufts, 9u * 64u * 64u, "%llu tufts", (unsigned long long)st.tufts);
    size_t count;
    tuft *tufts = meadow_tufts(&m, &count);
    cr_expect_eq(count, st.tufts);
    int off_ground = 0, outside = 0;
    for (size_t t = 0; t < count; t++) {
        off_ground += fabsf(tufts[t].y - 10.0f) > 1e-3f;
        outside += tufts[t].x < -32 || tufts[t].x > 64 || tufts[t].z < -32 || tufts[t].z > 64;
    }
    cr_expect_eq(off_ground, 0, "%d tufts not on the ground at 10 m", off_ground);
    cr_expect_eq(outside, 0);
    core_free(tufts, count * sizeof *tufts);
    meadow_close(&m);
}

/* The grass shows: drawn over the same frame without it, a good part of the ground changes, and
 * the changed pixels are green (more green than red or blue). */
Test(render_grass, grass_is_drawn_on_flat_ground) {
    meadow m;
    meadow_open(&m, GROUND_FLAT, 2, 3, 0, 0);
    for (int frame = 0; frame < 4; frame++) meadow_frame(&m, false);
    render_image bare = meadow_image(&m);
    meadow_frame(&m, true);
    render_image grassy = meadow_image(&m);
    int changed = 0, green = 0;
    for (int y = HEIGHT / 2; y < HEIGHT; y++)
        for (int x = 0; x < WIDTH; x++) {
            const uint8_t *a = render_pixel(&bare, x, y), *b = render_pixel(&grassy, x, y);
            int difference = abs(a[0] - b[0]) + abs(a[1] - b[1]) + abs(a[2] - b[2]);
            if (difference < 12) continue;
            changed++;
            green += b[1] > b[0] && b[1] > b[2];
        }
    int pixels = WIDTH * (HEIGHT / 2);
    cr_expect_gt(changed, pixels / 5, "%d of %d ground pixels changed by grass", changed, pixels);
    cr_expect_gt(green, changed * 9 / 10, "%d of %d changed pixels green", green, changed);
    cr_expect_gt(grass_system_stats(m.grass).tufts_drawn, 0);
    render_image_free(&bare);
    render_image_free(&grassy);
    meadow_close(&m);
}

/* The culling pass keeps every tuft well inside the view and nearer than 0.4·range (where every
 * tuft stands), and none beyond the range or well outside the frustum: the count it draws lies
 * between the two counts made here on the CPU from the tufts read back. It looks only at the
 * tufts of the mesh parts in view: fewer than the tufts placed, not fewer than it draws. */
Test(render_grass, culling_keeps_what_is_in_view_and_nothing_beyond) {
    meadow m;
    meadow_open(&m, GROUND_FLAT, 2, 2, 0, 0);
    for (int frame = 0; frame < 4; frame++) meadow_frame(&m, true);
    uint64_t drawn = grass_visible_tufts(m.grass);
    size_t count;
    tuft *tufts = meadow_tufts(&m, &count);
    terrain_frustum frustum = terrain_frustum_from_view(&m.view);
    const float range = 70.0f;                         /* GRASS_HIGH's */
    uint64_t surely = 0, possibly = 0;
    for (size_t t = 0; t < count; t++) {
        float p[3] = { tufts[t].x - (float)m.view.camera[0], tufts[t].y - (float)m.view.camera[1],
                       tufts[t].z - (float)m.view.camera[2] };
        float distance = sqrtf(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]), inside = 1e9f;
        for (int k = 0; k < 6; k++) {
            const float *plane = frustum.planes[k];
            inside = fminf(inside, plane[0] * p[0] + plane[1] * p[1] + plane[2] * p[2] + plane[3]);
        }
        surely += distance < 0.4f * range - 0.5f && inside > 1.0f;
        possibly += distance < range && inside > -2.0f;
    }
    cr_expect_gt(surely, 1000, "the view holds grass: %llu", (unsigned long long)surely);
    cr_expect(drawn >= surely && drawn <= possibly, "drawn %llu, between %llu and %llu", (unsigned long long)drawn,
              (unsigned long long)surely, (unsigned long long)possibly);
    cr_expect_lt(possibly, count, "some tufts are behind the camera");
    uint64_t looked = grass_system_stats(m.grass).tufts_drawn;
    cr_expect(looked >= drawn && looked < count, "looked at %llu tufts of %llu, drew %llu", (unsigned long long)looked,
              (unsigned long long)count, (unsigned long long)drawn);
    core_free(tufts, count * sizeof *tufts);
    meadow_close(&m);
}

/* Where grass must not grow, no tuft is placed at all (so none can be drawn). */
static uint64_t tufts_on(ground_kind kind, int64_t y_first, int64_t y_last) {
    meadow m;
    meadow_open(&m, kind, 2, 2, y_first, y_last);
    m.view.camera[1] = kind == GROUND_SLOPE_60 ? 60.0 : m.view.camera[1];
    for (int frame = 0; frame < 4; frame++) meadow_frame(&m, true);
    grass_system_stats_info st = grass_system_stats(m.grass);
    cr_expect_gt(st.patches, 0, "the ground has patches (placed, empty)");
    meadow_close(&m);
    return st.tufts;
}

/* α = (1 − n_y)·90° = 45° on a 60° slope, over the 35° limit (002 §3.3). */
Test(render_grass, none_on_a_sixty_degree_slope) { cr_expect_eq(tufts_on(GROUND_SLOPE_60, -2, 4), 0); }
Test(render_grass, none_under_water) { cr_expect_eq(tufts_on(GROUND_UNDER_WATER, -1, 0), 0); }
Test(render_grass, none_on_rocks) { cr_expect_eq(tufts_on(GROUND_ROCKS, 0, 0), 0); }

/* Sand carries grass thinly: a share 0.35 of the lattice (the grow factor of pure sand), so
 * about 0.35 · 36 864 = 12 902; the hash decides each cell, a binomial with σ ≈ 92. */
Test(render_grass, sand_carries_a_third_of_the_lattice) {
    uint64_t tufts = tufts_on(GROUND_SAND, 0, 0);
    cr_expect(tufts > 12902 - 600 && tufts < 12902 + 600, "%llu tufts", (unsigned long long)tufts);
}

/* In a cave the floor (10 m) has no sky: tufts grow only on the roof's top at 20 m. */
Test(render_grass, none_in_a_cave_only_on_its_roof) {
    meadow m;
    meadow_open(&m, GROUND_CAVE, 2, 2, 0, 0);
    m.view.camera[1] = 22;
    for (int frame = 0; frame < 4; frame++) meadow_frame(&m, true);
    size_t count;
    tuft *tufts = meadow_tufts(&m, &count);
    int on_floor = 0, on_roof = 0;
    for (size_t t = 0; t < count; t++) {
        on_floor += tufts[t].y < 15;
        on_roof += fabsf(tufts[t].y - 20.0f) < 1e-3f;
    }
    cr_expect_eq(on_floor, 0, "%d tufts on the cave's floor", on_floor);
    cr_expect_eq(on_roof, 9 * 64 * 64, "%d tufts on the roof", on_roof);
    core_free(tufts, count * sizeof *tufts);
    meadow_close(&m);
}

/* The same world gives the same tuft buffers, whatever the thread count and the order chunks
 * were meshed in. */
Test(render_grass, placement_is_the_same_every_run) {
    uint64_t digests[2];
    for (int run = 0; run < 2; run++) {
        meadow m;
        meadow_open(&m, GROUND_SAND, run + 1, 3, 0, 0);
        for (int frame = 0; frame < 4; frame++) meadow_frame(&m, true);
        cr_expect_eq(grass_system_stats(m.grass).patches, 9);
        digests[run] = grass_tufts_digest(m.grass);
        meadow_close(&m);
    }
    cr_expect_eq(digests[0], digests[1], "%llx vs %llx", (unsigned long long)digests[0], (unsigned long long)digests[1]);
}

/* A ball of radius 4 swept out at (16, 11, 16) leaves a bowl 3 m deep (everything within the
 * ball becomes air): in the frame that applies it the chunk is remeshed and its grass placed
 * again, so no tuft is left standing in the air over the bowl, and every tuft more than 8 m
 * from it is where it was (the lattice belongs to the world, not to the mesh). */
Test(render_grass, an_edit_replaces_the_grass_in_its_frame) {
    meadow m;
    meadow_open(&m, GROUND_FLAT, 2, 2, 0, 0);
    for (int frame = 0; frame < 4; frame++) meadow_frame(&m, true);
    size_t before_count;
    tuft *before = meadow_tufts(&m, &before_count);
    uint64_t placements = grass_system_stats(m.grass).placements;
    const double centre[1][3] = { { 16, 11, 16 } };
    cr_assert(terrain_ecs_edit(m.te, &(terrain_edit){ .tool = TERRAIN_EDIT_SWEEP,
                                                     .sweep = { .points = centre, .point_count = 1, .radius = 4 } }));
    meadow_frame(&m, true);
    cr_expect_gt(grass_system_stats(m.grass).placements, placements, "placed again in the frame of the edit");
    size_t after_count;
    tuft *after = meadow_tufts(&m, &after_count);
    int floating = 0;
    float lowest = 1e9f;
    size_t far_before = 0, far_after = 0;
    for (size_t t = 0; t < after_count; t++) {
        float d = hypotf(after[t].x - 16, after[t].z - 16);
        floating += d < 2.5f && after[t].y > 9.5f;
        if (d < 2.5f) lowest = fminf(lowest, after[t].y);
        far_after += d > 8;
    }
    for (size_t t = 0; t < before_count; t++) far_before += hypotf(before[t].x - 16, before[t].z - 16) > 8;
    cr_expect_eq(floating, 0, "%d tufts over the bowl at the old ground's height (lowest %g)", floating, (double)lowest);
    cr_expect_lt(after_count, before_count, "the bowl's steep walls lost their grass");
    cr_expect_eq(far_after, far_before, "away from the crater: %zu tufts, were %zu", far_after, far_before);
    core_free(before, before_count * sizeof *before);
    core_free(after, after_count * sizeof *after);
    meadow_close(&m);
}

/* Grass off: no patches, nothing drawn. */
Test(render_grass, quality_off_places_nothing) {
    meadow m;
    meadow_open(&m, GROUND_FLAT, 2, 2, 0, 0);
    grass_system_destroy(m.grass);
    m.grass = grass_system_create(&(grass_system_desc){ .gfx = m.gfx, .ecs = m.ecs, .world = m.world, .quality = GRASS_OFF });
    for (int frame = 0; frame < 3; frame++) meadow_frame(&m, true);
    cr_expect_eq(grass_system_stats(m.grass).patches, 0);
    meadow_close(&m);
}

Test(render_grass, bad_descriptions_are_refused) {
    gfx_context *gfx = render_offscreen(32, 32);
    ecs_world *ecs = ecs_world_create(NULL);
    render_capture_begin();
    cr_expect_null(grass_system_create(&(grass_system_desc){ .gfx = gfx }));
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ 0 });
    cr_expect_null(grass_system_create(&(grass_system_desc){ .gfx = gfx, .ecs = ecs, .world = world }));
    char *log = render_capture_end();
    cr_expect(strstr(log, "terrain_ecs_create"), "names the missing step: %s", log);
    free(log);
    grass_quality q;
    cr_expect(grass_parse_quality("high", &q) && q == GRASS_HIGH);
    cr_expect_not(grass_parse_quality("medium", &q));
    cr_expect_not(grass_parse_quality("", &q));
    terrain_world_destroy(world);
    ecs_world_destroy(ecs);
    gfx_context_destroy(gfx);
}
