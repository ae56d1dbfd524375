/* Rocks in the running world (modules/rocks): RockTiles follow the level-0 chunks, the rocks are
 * drawn (stone-coloured pixels where the pile is), far ones whole at LOD 2 in one batch, the same
 * rocks whatever the thread count, a rock layer dropped by an edit shows in the frame it is
 * committed, and digging removes them in that frame. Worlds are made by hand: a flat bedrock floor with a rock layer on part of it. */
#include "render_util.h"

#include "core/core.h"
#include "ecs/ecs.h"
#include "jobs/jobs.h"
#include "rocks/rocks.h"
#include "../rocks/rocks_test_cache.h"
#include "terrain/terrain.h"

#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DT (1.0f / 60.0f)
#define WIDTH 160
#define HEIGHT 90

/* Bedrock to 10 m; over x ∈ [8, 24), z ∈ [8, 24) a 1.5 m layer of rocks. */
static void yard_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    (void)user;
    terrain_stacks_builder_push(b, TERRAIN_BEDROCK, -TERRAIN_FLOOR_Y + 10);
    if (x >= 8 && x < 24 && z >= 8 && z < 24) terrain_stacks_builder_push(b, TERRAIN_ROCKS, 1.5f);
}

static terrain_stacks *yard_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, yard_column, user);
}

typedef struct yard {
    gfx_context *gfx;
    job_system *jobs;
    ecs_world *ecs;
    terrain_world *world;
    terrain_ecs *te;
    terrain_renderer *renderer;
    rocks_tileset *tiles;
    rocks_system *rocks;
    terrain_view view;
} yard;

static void yard_open(yard *y, int threads) {
    memset(y, 0, sizeof *y);
    y->gfx = render_offscreen(WIDTH, HEIGHT);
    cr_assert_not_null(y->gfx);
    y->jobs = job_system_create(&(job_system_desc){ .threads = threads });
    y->ecs = ecs_world_create(&(ecs_world_desc){ .jobs = y->jobs });
    terrain_generation_desc generation = terrain_generation_defaults(5);
    generation.sea_level = -50;
    y->world = terrain_world_create(&(terrain_world_desc){ .generation = generation, .generate = yard_chunk });
    y->te = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = y->ecs, .terrain = y->world });
    y->renderer = terrain_renderer_create(y->gfx, &(terrain_renderer_desc){ .sea_level = -50 });
    cr_assert_not_null(y->renderer);
    rocks_tileset_desc tiles = { .cells = 4, .voxels_per_cell = 6, .jobs = y->jobs };
    tiles.cache_path = rocks_test_cache(&tiles);
    y->tiles = rocks_tileset_create(&tiles);
    cr_assert_not_null(y->tiles);
    y->rocks = rocks_system_create(&(rocks_system_desc){ .gfx = y->gfx, .ecs = y->ecs, .world = y->world, .tiles = y->tiles });
    cr_assert_not_null(y->rocks);
    terrain_ecs_spawn_area(y->te, 0, 0, 1, 0, 0);
    y->view = (terrain_view){ .camera = { 16, 16, 34 }, .yaw = 0.0f, .pitch = -0.45f, .aspect = (float)WIDTH / HEIGHT };
}

static void yard_close(yard *y) {
    rocks_system_destroy(y->rocks);
    rocks_tileset_destroy(y->tiles);
    terrain_ecs_destroy(y->te);
    terrain_renderer_destroy(y->renderer);
    ecs_world_destroy(y->ecs);
    terrain_world_destroy(y->world);
    job_system_destroy(y->jobs);
    gfx_context_destroy(y->gfx);
}

static void yard_frame(yard *y, bool draw_rocks) {
    gfx_frame_begin(y->gfx);
    rocks_set_view(y->rocks, &y->view);
    terrain_ecs_set_view(y->te, &y->view);
    ecs_progress(y->ecs, DT);
    terrain_ecs_draw(y->te, y->renderer, &y->view);
    if (draw_rocks) rocks_draw(y->rocks, &y->view);
    gfx_frame_end(y->gfx);
}

static render_image yard_image(yard *y) {
    render_image image = { WIDTH, HEIGHT, core_alloc(WIDTH * HEIGHT * 4) };
    gfx_read_pixels(y->gfx, image.rgba);
    return image;
}

/* The pile shows: drawn over the same frame without it, many pixels change, to stone: a dull,
 * greyish colour (saturation (max − min)/max at most 0.35: the bare ground's green grass is
 * about 0.5, the sky's blue more) and not white. */
Test(render_rocks, a_rock_layer_is_drawn_as_rocks) {
    yard y;
    yard_open(&y, 2);
    for (int frame = 0; frame < 4; frame++) yard_frame(&y, false);
    render_image bare = yard_image(&y);
    yard_frame(&y, true);
    render_image rocky = yard_image(&y);
    rocks_system_stats_info st = rocks_system_stats(y.rocks);
    cr_expect_gt(st.instances, 50, "%llu rocks in a 16 × 16 × 1.5 m layer", (unsigned long long)st.instances);
    cr_expect_gt(st.instances_drawn, 0);
    int changed = 0, grey = 0;
    for (int py = 0; py < HEIGHT; py++)
        for (int px = 0; px < WIDTH; px++) {
            const uint8_t *a = render_pixel(&bare, px, py), *b = render_pixel(&rocky, px, py);
            if (abs(a[0] - b[0]) + abs(a[1] - b[1]) + abs(a[2] - b[2]) < 12) continue;
            changed++;
            int hi = b[0] > b[1] ? (b[0] > b[2] ? b[0] : b[2]) : (b[1] > b[2] ? b[1] : b[2]);
            int lo = b[0] < b[1] ? (b[0] < b[2] ? b[0] : b[2]) : (b[1] < b[2] ? b[1] : b[2]);
            grey += hi < 250 && (hi - lo) * 100 <= hi * 35 + 300;
        }
    cr_expect_gt(changed, WIDTH * HEIGHT / 20, "%d pixels changed by the rocks", changed);
    cr_expect_gt(grey, changed * 8 / 10, "%d of %d changed pixels stone-coloured", grey, changed);
    render_image_free(&bare);
    render_image_free(&rocky);
    yard_close(&y);
}

/* The triangles of LOD 2 of every rock placed (read from the RockTiles components themselves). */
static uint64_t yard_lod2_triangles(yard *y) {
    ecs_component tiles = ecs_component_lookup(y->ecs, "RockTiles");
    cr_assert_neq(tiles, 0);
    ecs_query *query = ecs_query_create(y->ecs, &(ecs_query_desc){ .with = { tiles } });
    uint64_t triangles = 0;
    ecs_iter it = ecs_query_iter(y->ecs, query);
    while (ecs_query_next(&it)) {
        const RockTiles *t = ecs_field(&it, 0);
        for (int i = 0; i < it.count; i++)
            for (uint32_t k = 0; k < t[i].placement.count; k++)
                triangles += y->tiles->rocks[t[i].placement.instances[k].rock].index_count[2] / 3;
    }
    ecs_query_destroy(y->ecs, query);
    return triangles;
}

/* The frame's rocks are one batch of the rocks' own levels: from 32–48 m (every seed past LOD 2's
 * latest start, 25 m × 1.25, and short of the shrinking's earliest end, 70 m × 0.75) with the
 * whole yard in view, every rock placed is drawn, and the batch holds exactly the sum of their
 * LOD 2 meshes' triangles, counted from the tile set. */
Test(render_rocks, far_rocks_are_drawn_whole_at_lod_2_in_one_batch) {
    yard y;
    yard_open(&y, 2);
    y.view = (terrain_view){ .camera = { 16, 28, 52 }, .yaw = 0.0f, .pitch = -0.47f, .aspect = (float)WIDTH / HEIGHT };
    for (int frame = 0; frame < 4; frame++) yard_frame(&y, true);
    rocks_system_stats_info st = rocks_system_stats(y.rocks);
    cr_assert_gt(st.instances, 50);
    cr_expect_eq(st.instances_drawn, st.instances, "%llu of %llu rocks drawn", (unsigned long long)st.instances_drawn,
                 (unsigned long long)st.instances);
    uint64_t expected = yard_lod2_triangles(&y);
    cr_expect_eq(st.triangles_drawn, expected, "%llu triangles drawn, %llu in the rocks' LOD 2",
                 (unsigned long long)st.triangles_drawn, (unsigned long long)expected);
    yard_close(&y);
}

Test(render_rocks, the_same_rocks_on_one_thread_and_on_two) {
    uint64_t digest[2];
    for (int t = 0; t < 2; t++) {
        yard y;
        yard_open(&y, t + 1);
        for (int frame = 0; frame < 4; frame++) yard_frame(&y, true);
        cr_assert_gt(rocks_system_stats(y.rocks).instances, 0);
        digest[t] = rocks_digest(y.rocks);
        yard_close(&y);
    }
    cr_expect_eq(digest[0], digest[1]);
}

/* Rocks dropped with the sand tool's rocks (a deposit of TERRAIN_ROCKS) are placed in the frame
 * the edit is committed, and a shaft swept through the layer takes its rocks in its frame. */
Test(render_rocks, edits_place_and_remove_rocks_in_their_frame) {
    yard y;
    yard_open(&y, 2);
    for (int frame = 0; frame < 4; frame++) yard_frame(&y, true);
    uint64_t before = rocks_system_stats(y.rocks).instances;
    cr_assert(terrain_ecs_edit(y.te, &(terrain_edit){ .tool = TERRAIN_EDIT_DEPOSIT,
        .deposit = { .material = TERRAIN_BRUSH_ROCKS, .x = 4, .z = 16, .radius = 3, .volume = 30 } }));
    yard_frame(&y, true);
    uint64_t dropped = rocks_system_stats(y.rocks).instances;
    cr_expect_gt(dropped, before, "a rock deposit shows in its frame: %llu → %llu rocks",
                 (unsigned long long)before, (unsigned long long)dropped);
    double points[2][3] = { { 16, 20, 16 }, { 16, 8, 16 } };
    cr_assert(terrain_ecs_edit(y.te, &(terrain_edit){ .tool = TERRAIN_EDIT_SWEEP,
        .sweep = { .points = (const double (*)[3])points, .point_count = 2, .radius = 3 } }));
    yard_frame(&y, true);
    uint64_t dug = rocks_system_stats(y.rocks).instances;
    cr_expect_lt(dug, dropped, "a shaft through the layer takes rocks in its frame: %llu → %llu",
                 (unsigned long long)dropped, (unsigned long long)dug);
    yard_close(&y);
}
