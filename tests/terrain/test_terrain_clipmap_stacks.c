/* The far terrain drawn from the stacks where chunks exist (002 §3.5): at a grid point whose four
 * columns are cached, a clipmap made with the world takes the height the chunks' meshes draw
 * there (hand-worked on flat and stepped worlds; checked against real meshes); generating,
 * editing and evicting chunks recompute the texels they touch; along a hole's border on a
 * generated world the clipmap meets the chunks' meshes. */
#include "../engine/test.h"
#include "terrain/terrain.h"
#include "terrain/terrain_internal.h"

#include "core/core.h"

#include <math.h>
#include <string.h>

/* ---- hand-made worlds ---- */

/* Bedrock up to 10.5 m everywhere, except that with `step` columns at x ≥ 0 reach 11 m and 10 m
 * at x < 0. */
typedef struct flat_world { bool step; float wall; } flat_world;   /* wall > 0: tops 10 and 10 + wall */

static void flat_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    (void)z;
    const flat_world *w = user;
    float top = w->wall > 0 ? (x >= 0 ? 10.0f + w->wall : 10.0f) : w->step ? (x >= 0 ? 11.0f : 10.0f) : 10.5f;
    terrain_stacks_builder_push(b, TERRAIN_BEDROCK, top - TERRAIN_FLOOR_Y);
}

static terrain_stacks *flat_generate(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, flat_column, user);
}

static terrain_world *flat_world_create(flat_world *w) {
    return terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(3),
                                                       .generate = flat_generate, .generate_user = w });
}

static terrain_clipmap *world_clipmap(terrain_world *world, float spacing, int cells, int levels, float mesh_step) {
    return terrain_clipmap_create(&(terrain_clipmap_desc){ .levels = levels, .cells = cells, .finest_spacing = spacing,
                                                           .generation = *terrain_world_generation(world),
                                                           .world = world, .mesh_step = mesh_step });
}

/* The generator's G at a level's grid point: what a texel holds where no chunk is cached. */
static float ground_at(const terrain_generation_desc *p, const terrain__clipmap_level_info *info, int64_t i, int64_t k) {
    float g;
    terrain__ground_row_spaced(p, (double)i * info->spacing, info->spacing, (double)k * info->spacing, 1, (float)info->spacing,
                               &g, NULL);
    return g;
}

/* Whether the four columns around grid point (x, z) metres (x − 1, x and z − 1, z) lie in the
 * chunks [lo, hi]² (the points are at whole metres). */
static bool corner_in(double x, double z, int64_t lo, int64_t hi) {
    double min = (double)lo * TERRAIN_CHUNK_COLUMNS, max = (double)(hi + 1) * TERRAIN_CHUNK_COLUMNS;
    return x >= min + 1 && x <= max - 1 && z >= min + 1 && z <= max - 1;
}

/* ---- the real mesh's surface at a sample point ---- */

/* The topmost vertex a level-`level` mesh puts on the vertical line through grid point (x, z)
 * (metres, on the level's sample grid): the crossing of one of its vertical edges. NAN if none. */
static float mesh_top_at(terrain_world *world, int level, double x, double z, float near_y) {
    double size = (double)TERRAIN_MESH_CELLS * ldexp(1.0, level);
    int64_t cx = (int64_t)floor(x / size), cz = (int64_t)floor(z / size);
    float best = NAN;
    for (int64_t cy = (int64_t)floor((near_y - 12.0) / size); cy <= (int64_t)floor((near_y + 12.0) / size); cy++) {
        terrain_mesh mesh;
        cr_assert(terrain_mesh_chunk(world, cx, cy, cz, &(terrain_lod_desc){ .level = level }, &mesh));
        for (uint32_t v = 0; v < mesh.vertex_count; v++) {
            const float *p = mesh.vertices[v].position;
            double wx = mesh.origin[0] + p[0], wy = mesh.origin[1] + p[1], wz = mesh.origin[2] + p[2];
            if (fabs(wx - x) < 1e-4 && fabs(wz - z) < 1e-4 && !(wy <= best)) best = (float)wy;
        }
        terrain_mesh_free(&mesh);
    }
    return best;
}

/* ---- heights ---- */

Test(terrain_clipmap_stacks, a_cached_chunks_grid_points_take_the_stacks_top) {
    flat_world w = { .step = false };
    terrain_world *world = flat_world_create(&w);
    for (int64_t cz = -1; cz <= 0; cz++)
        for (int64_t cx = -1; cx <= 0; cx++) terrain_world_stacks(world, (terrain_chunk_coord){ cx, cz });
    terrain_clipmap *c = world_clipmap(world, 4.0f, 32, 3, 1.0f);
    terrain_clipmap_update(c, (double[3]){ 0, 20, 0 });
    const terrain_generation_desc *p = terrain_world_generation(world);
    int inside = 0, outside = 0;
    for (int l = 0; l < 3; l++) {
        terrain__clipmap_level_info info = terrain__clipmap_level(c, l);
        for (int64_t k = info.first[1] - 1; k <= info.first[1] + info.cells + 1; k++)
            for (int64_t i = info.first[0] - 1; i <= info.first[0] + info.cells + 1; i++) {
                double x = (double)i * info.spacing, z = (double)k * info.spacing;
                float texel = terrain__clipmap_texel(c, l, i, k);
                if (corner_in(x, z, -1, 0)) {
                    /* Four columns topped at 10.5: f(10) = 0.5, f(11) = −0.5, the crossing 10.5. */
                    cr_assert_eq(texel, 10.5f, "level %d (%g, %g): %f", l, x, z, texel);
                    inside++;
                } else {
                    cr_assert_eq(texel, ground_at(p, &info, i, k), "level %d (%g, %g) outside the chunks is G", l, x, z);
                    outside++;
                }
            }
    }
    cr_assert_gt(inside, 0);
    cr_assert_gt(outside, inside);
    /* The drawn surface too, away from any morph: level 0 around the camera. */
    cr_assert_float_eq(terrain_clipmap_height(c, 5.3, -7.1), 10.5f, 1e-6);
    terrain_clipmap_destroy(c);
    terrain_world_destroy(world);
}

Test(terrain_clipmap_stacks, heights_are_what_a_mesh_of_the_steps_spacing_draws) {
    flat_world w = { .step = true };
    terrain_world *world = flat_world_create(&w);
    for (int64_t cz = -1; cz <= 0; cz++)
        for (int64_t cx = -1; cx <= 0; cx++) terrain_world_stacks(world, (terrain_chunk_coord){ cx, cz });
    /* Step 1 at the step x = 0: tops 10, 10, 11, 11; f(10) = (2·1 + 2·2)/4 − 1 = 0.5, f(11) =
     * (0 + 2·1)/4 − 1 = −0.5: 10.5, the four tops' mean. Away from it, the tops. */
    terrain_clipmap *c = world_clipmap(world, 1.0f, 32, 1, 1.0f);
    terrain_clipmap_update(c, (double[3]){ 0, 20, 0 });
    cr_assert_eq(terrain__clipmap_texel(c, 0, 0, 3), 10.5f);
    cr_assert_eq(terrain__clipmap_texel(c, 0, -4, 3), 10.0f);
    cr_assert_eq(terrain__clipmap_texel(c, 0, 4, 3), 11.0f);
    terrain_clipmap_destroy(c);
    /* Step 4 (a level-2 ring's meshes): samples at 8 and 12 m. Tops of 11 m: f(8) = 1 (the whole
     * window solid), f(12) = −1 (none of it): the crossing halfway, 10; tops of 10 m likewise. */
    c = world_clipmap(world, 4.0f, 16, 1, 4.0f);
    terrain_clipmap_update(c, (double[3]){ 0, 20, 0 });
    cr_assert_eq(terrain__clipmap_texel(c, 0, 1, 1), 10.0f);
    cr_assert_eq(terrain__clipmap_texel(c, 0, -1, 1), 10.0f);
    terrain_clipmap_destroy(c);
    /* The same numbers from the meshes themselves: their vertical edges through the points. */
    cr_assert_float_eq(mesh_top_at(world, 0, 0, 3, 10.5f), 10.5f, 1e-4);
    cr_assert_float_eq(mesh_top_at(world, 0, 4, 3, 11.0f), 11.0f, 1e-4);
    cr_assert_float_eq(mesh_top_at(world, 2, 4, 4, 10.0f), 10.0f, 1e-4);
    terrain_world_destroy(world);
}

/* A 4 m wall through the corner x = 0 (tops 10 m for x < 0, 14 m for x ≥ 0): there two of the
 * four columns are solid and two are air from 11 to 13 m, so f = L/4 − 1 is exactly 0 all along
 * that stretch (f(10) = (2·1 + 2·2)/4 − 1 = 0.5, f(14) = (2·1)/4 − 1 = −0.5). The mesh draws the
 * wall's face through the corner, up to 13 m: vertices on the x-edges from the corner (f = 0,
 * air) to x = 1 (f = 1) at t = 0. The texel is the face's top, 13 m, as the mesh's topmost
 * vertex there; reading f = 0 as air, it was 11 m (the crossing between 10 and 11). */
Test(terrain_clipmap_stacks, a_wall_through_the_corner_takes_its_top) {
    flat_world w = { .wall = 4.0f };
    terrain_world *world = flat_world_create(&w);
    for (int64_t cz = -1; cz <= 0; cz++)
        for (int64_t cx = -1; cx <= 0; cx++) terrain_world_stacks(world, (terrain_chunk_coord){ cx, cz });
    terrain_clipmap *c = world_clipmap(world, 1.0f, 32, 1, 1.0f);
    terrain_clipmap_update(c, (double[3]){ 0, 20, 0 });
    cr_expect_eq(terrain__clipmap_texel(c, 0, 0, 3), 13.0f);
    cr_expect_float_eq(mesh_top_at(world, 0, 0, 3, 12.0f), 13.0f, 1e-4);
    cr_expect_eq(terrain__clipmap_texel(c, 0, 4, 3), 14.0f, "on the high side, its top");
    terrain_clipmap_destroy(c);
    terrain_world_destroy(world);
}

/* ---- chunks that come, change and go ---- */

Test(terrain_clipmap_stacks, generated_edited_and_evicted_chunks_update_their_texels) {
    flat_world w = { .step = false };
    terrain_world *world = flat_world_create(&w);
    terrain_clipmap *c = world_clipmap(world, 1.0f, 64, 2, 1.0f);
    const terrain_generation_desc *p = terrain_world_generation(world);
    terrain_clipmap_update(c, (double[3]){ 0, 20, 0 });
    terrain__clipmap_level_info info = terrain__clipmap_level(c, 0);
    cr_assert_eq(terrain__clipmap_texel(c, 0, 16, 16), ground_at(p, &info, 16, 16), "nothing cached: G");

    /* Generated: chunk (0, 0) and its neighbours, so that (16, 16) and (0, 0)'s corners are in. */
    for (int64_t cz = -1; cz <= 0; cz++)
        for (int64_t cx = -1; cx <= 0; cx++) terrain_world_stacks(world, (terrain_chunk_coord){ cx, cz });
    uint64_t texels = terrain_clipmap_update(c, (double[3]){ 0, 20, 0 });
    cr_assert_gt(texels, 0u, "the camera did not move: only the chunks' texels");
    cr_assert_eq(terrain__clipmap_texel(c, 0, 16, 16), 10.5f);
    cr_assert_eq(terrain__clipmap_texel(c, 1, 8, 8), 10.5f, "the coarser level too");

    /* Edited: a dug pit (a carving sculpt of radius 8 at (16, 10.5, 16)). */
    terrain_chunk_coord changed[8];
    int n = terrain_world_edit(world, &(terrain_edit){ .tool = TERRAIN_EDIT_SCULPT_CARVE,
                                                       .sculpt = { .target = { 16, 10.5, 16 }, .radius = 8 } },
                               changed, 8);
    cr_assert_gt(n, 0);
    float top = terrain_world_top(world, 16.5, 16.5);
    cr_assert_lt(top, 10.25f, "the pit is deeper than a quarter metre: %f", top);
    terrain_clipmap_update(c, (double[3]){ 0, 20, 0 });
    float texel = terrain__clipmap_texel(c, 0, 16, 16);
    cr_assert_lt(texel, 10.25f, "the pit shows in the clipmap: %f", texel);
    cr_assert_float_eq(texel, mesh_top_at(world, 0, 16, 16, top), 1e-3, "as the mesh draws it");
    cr_assert_eq(terrain__clipmap_texel(c, 0, 2, 2), 10.5f, "away from the pit, as before");

    /* Evicted: the cache shrinks to nothing; G comes back (the edit is pinned without a log, so
     * that chunk stays and keeps its pit). */
    terrain_world_set_max_chunks(world, 1);
    terrain_world_trim(world);
    terrain_clipmap_update(c, (double[3]){ 0, 20, 0 });
    cr_assert_eq(terrain__clipmap_texel(c, 0, 16, 16), texel, "the edited chunk is kept");
    cr_assert_eq(terrain__clipmap_texel(c, 0, -16, -16), ground_at(p, &info, -16, -16), "an evicted chunk's texels are G again");
    terrain_clipmap_destroy(c);
    terrain_world_destroy(world);
}

/* ---- the seam ---- */

/* A 2 × 2-chunk hole at level 0 on seed 1: at every sample of the meshes' border (1 m apart) the
 * clipmap's drawn surface (its finest level, unmorphed there) is within 0.25 m of the mesh's;
 * with G alone (no world) it is not. The meshes are the streamer's: terrain_mesh_chunk. */
Test(terrain_clipmap_stacks, the_seam_gap_along_a_holes_border_is_within_a_quarter_metre) {
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(1) });
    enum { SIDE = 64, SAMPLES = 4 * SIDE };
    const double lo = -32.0, hi = 32.0;
    for (int64_t cz = -2; cz <= 1; cz++)
        for (int64_t cx = -2; cx <= 1; cx++) terrain_world_stacks(world, (terrain_chunk_coord){ cx, cz });
    /* The border's samples, and the mesh chunks' y range around their tops. */
    double points[SAMPLES][2];
    float mesh_top[SAMPLES], low = INFINITY, high = -INFINITY;
    for (int n = 0; n < SAMPLES; n++) {
        int side = n / SIDE;
        double t = lo + n % SIDE;
        points[n][0] = side < 2 ? t : (side == 2 ? lo : hi);
        points[n][1] = side < 2 ? (side == 0 ? lo : hi) : t;
        mesh_top[n] = NAN;
        float top = terrain_world_top(world, points[n][0] + 0.5, points[n][1] + 0.5);
        low = fminf(low, top);
        high = fmaxf(high, top);
    }
    for (int64_t cz = -1; cz <= 0; cz++)
        for (int64_t cx = -1; cx <= 0; cx++)
            for (int64_t cy = (int64_t)floorf((low - 4) / 32); cy <= (int64_t)floorf((high + 4) / 32); cy++) {
                terrain_mesh mesh;
                cr_assert(terrain_mesh_chunk(world, cx, cy, cz, NULL, &mesh));
                for (uint32_t v = 0; v < mesh.vertex_count; v++) {
                    const float *p = mesh.vertices[v].position;
                    double x = mesh.origin[0] + p[0], y = mesh.origin[1] + p[1], z = mesh.origin[2] + p[2];
                    /* A vertical edge's crossing on the border: whole x and z, one of them a side. */
                    if (x != floor(x) || z != floor(z) || !(x == lo || x == hi || z == lo || z == hi)) continue;
                    int side = z == lo ? 0 : z == hi ? 1 : x == lo ? 2 : 3;
                    double t = side < 2 ? x : z;
                    if (t < lo || t >= hi) continue;
                    int n = side * SIDE + (int)(t - lo);
                    if (!(y <= mesh_top[n])) mesh_top[n] = (float)y;
                }
                terrain_mesh_free(&mesh);
            }
    terrain_clipmap *c = world_clipmap(world, 1.0f, 128, 1, 1.0f);
    terrain_clipmap *plain = terrain_clipmap_create(&(terrain_clipmap_desc){ .levels = 1, .cells = 128, .finest_spacing = 1.0f,
                                                                             .generation = *terrain_world_generation(world) });
    terrain_clipmap_update(c, (double[3]){ 0, 30, 0 });
    terrain_clipmap_update(plain, (double[3]){ 0, 30, 0 });
    float worst = 0, worst_plain = 0;
    int samples = 0;
    for (int n = 0; n < SAMPLES; n++) {
        if (isnan(mesh_top[n])) continue;
        worst = fmaxf(worst, fabsf(mesh_top[n] - terrain_clipmap_height(c, points[n][0], points[n][1])));
        worst_plain = fmaxf(worst_plain, fabsf(mesh_top[n] - terrain_clipmap_height(plain, points[n][0], points[n][1])));
        samples++;
    }
    cr_assert_gt(samples, SAMPLES * 9 / 10, "%d samples", samples);
    cr_assert_leq(worst, 0.25f, "largest gap %.3f m", worst);
    cr_assert_gt(worst_plain, 0.25f, "G alone leaves %.3f m: the test can tell", worst_plain);
    terrain_clipmap_destroy(plain);
    terrain_clipmap_destroy(c);
    terrain_world_destroy(world);
}

/* ---- level 0 on the rings' grid, and the seam's own heights ---- */

/* Bedrock rolling by ±3 m over 10 m (hand-made: cheap to cache hundreds of chunks). */
static void rolling_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    (void)user;
    float top = 10.0f + 3.0f * sinf((float)x / 7.0f) * cosf((float)z / 5.0f);
    terrain_stacks_builder_push(b, TERRAIN_BEDROCK, top - TERRAIN_FLOOR_Y);
}

static terrain_stacks *rolling_generate(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, rolling_column, user);
}

/* With centre_snap 128 m (the default rings' coarsest chunk) level 0 is centred on the camera
 * snapped to 128 m, and still every finer border vertex lies on the coarser level's drawn
 * surface (which is unmorphed there), for cameras anywhere in the snap cell. */
Test(terrain_clipmap_stacks, a_coarse_centre_snap_keeps_the_levels_crack_free) {
    terrain_clipmap *c = terrain_clipmap_create(&(terrain_clipmap_desc){
        .levels = 4, .cells = 64, .finest_spacing = 4.0f, .centre_snap = 64.0f, .generation = terrain_generation_defaults(5) });
    const double cameras[][2] = { { 31.9, -31.9 }, { 1000.0 + 31.0, 1000.0 - 30.0 }, { -5000.0, 777.0 }, { 95.0, 96.9 } };
    for (size_t n = 0; n < sizeof cameras / sizeof cameras[0]; n++) {
        double camera[3] = { cameras[n][0], 40.0, cameras[n][1] };
        terrain_clipmap_update(c, camera);
        terrain__clipmap_level_info level0 = terrain__clipmap_level(c, 0);
        for (int a = 0; a < 2; a++) {
            double centre = (double)(level0.first[a] + 32) * 4.0;
            cr_assert_eq(centre, 64.0 * floor(cameras[n][a] / 64.0 + 0.5), "camera %zu axis %d: level 0 centred on the snap", n, a);
        }
        for (int l = 0; l + 1 < 4; l++) {
            terrain__clipmap_level_info fine = terrain__clipmap_level(c, l), coarse = terrain__clipmap_level(c, l + 1);
            for (int j = 0; j <= 64; j++)
                for (int side = 0; side < 4; side++) {
                    int i = side == 0 ? j : side == 1 ? j : side == 2 ? 0 : 64, k = side == 0 ? 0 : side == 1 ? 64 : j;
                    float position[2], height;
                    terrain__clipmap_vertex(c, l, i, k, camera, position, &height);
                    /* The coarser vertices at or before and after it (fine index parity). */
                    /* first is even, so grid index first + i halves to first/2 + i/2. */
                    int ci = (int)(fine.first[0] / 2 + i / 2 - coarse.first[0]), ck = (int)(fine.first[1] / 2 + k / 2 - coarse.first[1]);
                    float p0[2], p1[2], h0, h1;
                    terrain__clipmap_vertex(c, l + 1, ci, ck, camera, p0, &h0);
                    terrain__clipmap_vertex(c, l + 1, ci + (i & 1), ck + (k & 1), camera, p1, &h1);
                    cr_assert_eq(h0, terrain__clipmap_texel(c, l + 1, coarse.first[0] + ci, coarse.first[1] + ck),
                                 "camera %zu level %d: the coarser level is unmorphed under the finer border", n, l + 1);
                    cr_assert_eq(height, 0.5f * (h0 + h1), "camera %zu level %d vertex (%d, %d) on the coarser edge", n, l, i, k);
                }
        }
    }
    terrain_clipmap_destroy(c);
}

/* On the hole's border every vertex keeps its own texel — the chunks' height — even where the
 * level morphs (there: level 0's own border, the hole's border with the rings' snap), so the
 * clipmap meets the meshes at every one of its border vertices. */
Test(terrain_clipmap_stacks, on_the_holes_border_vertices_keep_the_chunks_height) {
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(3),
                                                                       .generate = rolling_generate });
    for (int64_t cz = -10; cz < 10; cz++)
        for (int64_t cx = -10; cx < 10; cx++) terrain_world_stacks(world, (terrain_chunk_coord){ cx, cz });
    terrain_clipmap *c = terrain_clipmap_create(&(terrain_clipmap_desc){
        .levels = 3, .cells = 64, .finest_spacing = 4.0f, .centre_snap = 64.0f, .generation = terrain_generation_defaults(3),
        .world = world, .mesh_step = 1.0f });
    /* The camera 30 m off the snap's centre (0, 0); the hole the rings' square there, ±128 m. */
    double camera[3] = { 30.0, 20.0, -30.0 };
    terrain_clipmap_update(c, camera);
    terrain_clipmap_set_hole(c, (double[2]){ -128, -128 }, (double[2]){ 128, 128 });
    int checked = 0, morphing = 0;
    for (double t = -128; t <= 128; t += 4.0)
        for (int side = 0; side < 4; side++) {
            double x = side < 2 ? t : (side == 2 ? -128 : 128), z = side < 2 ? (side == 0 ? -128 : 128) : t;
            /* Level 0's vertex there: its own border, where the morph is complete. */
            int64_t i = (int64_t)llround(x / 4.0), k = (int64_t)llround(z / 4.0);
            terrain__clipmap_level_info info = terrain__clipmap_level(c, 0);
            float texel = terrain__clipmap_texel(c, 0, i, k), position[2], height;
            terrain__clipmap_vertex(c, 0, (int)(i - info.first[0]), (int)(k - info.first[1]), camera, position, &height);
            cr_assert_eq(height, texel, "(%g, %g) keeps its texel", x, z);
            cr_assert_float_eq(terrain_clipmap_height(c, x, z), texel, 1e-4, "(%g, %g) as drawn", x, z);
            morphing += (i & 1) || (k & 1);
            checked++;
        }
    cr_assert_gt(morphing, 100, "odd vertices, which a full morph would move onto the coarser edges");
    (void)checked;
    terrain_clipmap_destroy(c);
    terrain_world_destroy(world);
}

/* With an edit log, an edited chunk is evictable (the log can make it again), and the clipmap
 * makes it again when its texels are asked for after it left the cache: the pit dug in it shows
 * from afar whenever it is in the clipmap, not only while the chunk is cached. Unedited chunks
 * evicted are G again, as without a log. */
Test(terrain_clipmap_stacks, an_evicted_edited_chunk_is_made_again_from_the_log) {
    flat_world w = { .step = false };
    terrain_generation_desc generation = terrain_generation_defaults(3);
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = terrain_generation_key(&generation) });
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = generation, .generate = flat_generate,
                                                                       .generate_user = &w, .edits = log });
    terrain_clipmap *c = world_clipmap(world, 1.0f, 64, 2, 1.0f);
    for (int64_t cz = -1; cz <= 0; cz++)
        for (int64_t cx = -1; cx <= 0; cx++) terrain_world_stacks(world, (terrain_chunk_coord){ cx, cz });
    cr_assert_gt(terrain_world_edit(world, &(terrain_edit){ .tool = TERRAIN_EDIT_SCULPT_CARVE,
                                                            .sculpt = { .target = { 16, 10.5, 16 }, .radius = 8 } },
                                    NULL, 0), 0);
    terrain_clipmap_update(c, (double[3]){ 0, 20, 0 });
    float pit = terrain__clipmap_texel(c, 0, 16, 16);
    cr_assert_lt(pit, 10.25f, "the pit shows: %f", pit);
    terrain__clipmap_level_info info = terrain__clipmap_level(c, 0);
    /* A chunk far away used last, so that it is the one the cache keeps. */
    terrain_world_stacks(world, (terrain_chunk_coord){ 40, 40 });
    terrain_world_set_max_chunks(world, 1);
    terrain_world_trim(world);
    cr_assert_null(terrain__world_cached(world, (terrain_chunk_coord){ 0, 0 }), "the edited chunk was evicted");
    terrain_clipmap_update(c, (double[3]){ 0, 20, 0 });
    cr_assert_eq(terrain__clipmap_texel(c, 0, 16, 16), pit, "the evicted pit is made again from the log");
    cr_assert_eq(terrain__clipmap_texel(c, 0, -16, -16), ground_at(terrain_world_generation(world), &info, -16, -16),
                 "an unedited chunk evicted: G");
    terrain_clipmap_destroy(c);
    terrain_world_destroy(world);
    terrain_edit_log_destroy(log);
}
