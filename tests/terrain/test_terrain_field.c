/* The convolution field (000 §3.3): f = 2·V/(8σ³) − 1 with V the volume of sand and bedrock in
 * the cube of radius σ. Expectations come from the formula by hand (a half-filled kernel is 0,
 * a full one 1, an empty one −1; a box layer's V is the product of three interval overlaps), and
 * the grid sampler is checked against the direct summation reference and against itself across
 * regions (shared samples must be bit-identical). */
#include "../engine/test.h"
#include "core/core.h"
#include "terrain/terrain.h"

#include <math.h>
#include <string.h>

/* ---- worlds whose chunks the test controls --------------------------------------------------- */

/* Every column comes from column(gx, gz, builder): the layers of global column (gx, gz). */
typedef struct hand_world {
    void (*column)(const struct hand_world *world, int64_t gx, int64_t gz, terrain_stacks_builder *b);
    double ground;                     /* flat ground height */
    double box_min[3], box_max[3];     /* a floating box of bedrock (columns within its x/z range) */
} hand_world;

static void hand_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    const hand_world *hand = user;
    hand->column(hand, x, z, b);
}

static terrain_stacks *hand_generate(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, hand_column, user);
}

static terrain_world *hand_world_create(hand_world *hand) {
    return terrain_world_create(&(terrain_world_desc){ .generate = hand_generate, .generate_user = hand });
}

static void flat_column(const hand_world *w, int64_t gx, int64_t gz, terrain_stacks_builder *b) {
    (void)gx, (void)gz;
    terrain_stacks_builder_push(b, TERRAIN_BEDROCK, (float)(w->ground - TERRAIN_FLOOR_Y));
}

/* Air from the floor up to box_min.y, then bedrock to box_max.y, inside the box's columns. */
static void box_column(const hand_world *w, int64_t gx, int64_t gz, terrain_stacks_builder *b) {
    if ((double)gx < w->box_min[0] || (double)gx + 1 > w->box_max[0] || (double)gz < w->box_min[2] ||
        (double)gz + 1 > w->box_max[2])
        return;
    terrain_stacks_builder_push(b, TERRAIN_AIR, (float)(w->box_min[1] - TERRAIN_FLOOR_Y));
    terrain_stacks_builder_push(b, TERRAIN_BEDROCK, (float)(w->box_max[1] - w->box_min[1]));
}

static double overlap(double a0, double a1, double b0, double b1) {
    double lo = fmax(a0, b0), hi = fmin(a1, b1);
    return hi > lo ? hi - lo : 0.0;
}

/* f at p for the box world, from the formula: V = Π overlap(box, [p − σ, p + σ]). */
static double box_field(const hand_world *w, const double p[3], double sigma) {
    double volume = 1.0;
    for (int a = 0; a < 3; a++) volume *= overlap(w->box_min[a], w->box_max[a], p[a] - sigma, p[a] + sigma);
    return 2.0 * volume / (8.0 * sigma * sigma * sigma) - 1.0;
}

static float field_value(const terrain_field *f, int x, int y, int z) {
    return f->values[((size_t)z * f->ny + y) * f->nx + x];
}

/* ---- hand-computed values ---------------------------------------------------------------------- */

Test(terrain_field, half_full_and_empty_kernels) {
    hand_world hand = { .column = flat_column, .ground = 10.0 };
    terrain_world *world = hand_world_create(&hand);
    const float sigmas[] = { 1.0f, 0.5f, 1.5f, 2.0f, 3.25f };
    for (size_t s = 0; s < CORE_COUNTOF(sigmas); s++) {
        float sigma = sigmas[s];
        /* The kernel centred on the ground plane holds exactly half its volume: f = 0. */
        cr_expect_float_eq(terrain_field_at(world, 3.0, 10.0, -7.0, sigma), 0.0f, 1e-6f, "sigma %g", (double)sigma);
        cr_expect_float_eq(terrain_field_at(world, 3.0, 10.0 - sigma - 0.5, -7.0, sigma), 1.0f, 1e-6f);
        cr_expect_float_eq(terrain_field_at(world, 3.0, 10.0 + sigma + 0.5, -7.0, sigma), -1.0f, 1e-6f);
        /* A quarter of the way up the kernel: V = (2σ)²·(σ + σ/2), f = 2V/(8σ³) − 1 = 0.5. */
        cr_expect_float_eq(terrain_field_at(world, 0.25, 10.0 - sigma / 2, 0.75, sigma), 0.5f, 1e-6f);
        terrain_field field;
        cr_assert(terrain_field_sample(world, &(terrain_field_desc){ .first = { -3, 7, 30 }, .size = { 7, 7, 5 },
                                                                     .sigma = sigma },
                                       &field));
        cr_assert_eq(field.nx, 7);
        cr_expect_float_eq(field.origin[1], 7.0, 0.0);
        for (int z = 0; z < 5; z++)
            for (int y = 0; y < 7; y++)
                for (int x = 0; x < 7; x++) {
                    double h = 7.0 + y - 10.0;   /* sample height above the ground */
                    double solid = fmin(fmax(sigma - h, 0.0), 2.0 * sigma);
                    double expected = solid / sigma - 1.0;   /* 2·(2σ)²·solid / 8σ³ − 1 */
                    cr_expect_float_eq(field_value(&field, x, y, z), (float)expected, 2e-6f,
                                       "sigma %g sample (%d, %d, %d)", (double)sigma, x, y, z);
                }
        terrain_field_free(&field);
    }
    /* sigma 0 means one column. */
    cr_expect_float_eq(terrain_field_at(world, 0.0, 10.5, 0.0, 0.0f), -0.5f, 1e-6f);
    terrain_world_destroy(world);
}

Test(terrain_field, box_layer_against_analytic_volume) {
    hand_world hand = { .column = box_column, .box_min = { -3, 4.25, 29 }, .box_max = { 5, 9.5, 34 } };
    terrain_world *world = hand_world_create(&hand);
    const float sigmas[] = { 1.0f, 0.75f, 1.5f, 2.5f };
    int checked = 0;
    for (size_t s = 0; s < CORE_COUNTOF(sigmas); s++) {
        double sigma = sigmas[s];
        /* Scattered points (not on the grid), including ones straddling every face and corner. */
        for (int n = 0; n < 400; n++) {
            uint64_t h = core_hash_u64((uint64_t)n * 7919 + s);
            double p[3] = { -6.0 + (double)(h & 0xffff) / 65536.0 * 14.0,
                            1.0 + (double)((h >> 16) & 0xffff) / 65536.0 * 12.0,
                            26.0 + (double)((h >> 32) & 0xffff) / 65536.0 * 11.0 };
            cr_expect_float_eq(terrain_field_at(world, p[0], p[1], p[2], (float)sigma), (float)box_field(&hand, p, sigma),
                               2e-6f, "sigma %g at (%g, %g, %g)", sigma, p[0], p[1], p[2]);
            checked++;
        }
        /* The grid sampler on a region around the box. */
        terrain_field field;
        cr_assert(terrain_field_sample(world, &(terrain_field_desc){ .first = { -7, 1, 25 }, .size = { 15, 12, 13 },
                                                                     .sigma = (float)sigma },
                                       &field));
        for (int z = 0; z < field.nz; z++)
            for (int y = 0; y < field.ny; y++)
                for (int x = 0; x < field.nx; x++) {
                    double p[3] = { -7 + x, 1 + y, 25 + z };
                    cr_expect_float_eq(field_value(&field, x, y, z), (float)box_field(&hand, p, sigma), 2e-6f,
                                       "sigma %g grid (%d, %d, %d)", sigma, x, y, z);
                    checked++;
                }
        terrain_field_free(&field);
    }
    cr_expect_gt(checked, 1000);
    terrain_world_destroy(world);
}

/* ---- the sampler against the reference, on generated terrain ----------------------------- */

static int64_t surface_height(terrain_world *world, int64_t cx, int64_t cz) {
    const terrain_stacks *stacks = terrain_world_stacks(world, (terrain_chunk_coord){ cx, cz });
    return (int64_t)floor(terrain_stacks_top(stacks, 16, 16));
}

Test(terrain_field, grid_equals_direct_summation_on_generated_terrain) {
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(7) });
    int64_t ground = surface_height(world, 0, 0);
    const float sigmas[] = { 0.0f, 1.37f, 2.0f };
    for (size_t s = 0; s < CORE_COUNTOF(sigmas); s++) {
        /* Across the corner of four chunks, so the kernel reads neighbours on every side. */
        terrain_field_desc desc = { .first = { -17, ground - 12, -9 }, .size = { 34, 24, 21 }, .sigma = sigmas[s] };
        terrain_field field;
        cr_assert(terrain_field_sample(world, &desc, &field));
        int inside = 0, outside = 0;
        for (int z = 0; z < field.nz; z++)
            for (int y = 0; y < field.ny; y++)
                for (int x = 0; x < field.nx; x++) {
                    float value = field_value(&field, x, y, z);
                    float reference = terrain_field_at(world, (double)(desc.first[0] + x), (double)(desc.first[1] + y),
                                                       (double)(desc.first[2] + z), sigmas[s]);
                    cr_expect_float_eq(value, reference, 1e-5f, "sigma %g sample (%d, %d, %d)", (double)sigmas[s], x, y, z);
                    inside += value > 0, outside += value < 0;
                }
        cr_expect_gt(inside, 0, "the region holds ground");
        cr_expect_gt(outside, 0, "and air");
        terrain_field_free(&field);
    }
    terrain_world_destroy(world);
}

/* Samples that two regions share are bit-identical, whatever the regions' positions and sizes. */
static void expect_shared_samples_identical(terrain_world *world, const terrain_field_desc *a_desc,
                                            const terrain_field_desc *b_desc) {
    terrain_field a, b;
    cr_assert(terrain_field_sample(world, a_desc, &a));
    cr_assert(terrain_field_sample(world, b_desc, &b));
    int64_t lo[3], hi[3];
    for (int i = 0; i < 3; i++) {
        lo[i] = CORE_MAX(a_desc->first[i], b_desc->first[i]);
        hi[i] = CORE_MIN(a_desc->first[i] + a_desc->size[i], b_desc->first[i] + b_desc->size[i]);
        cr_assert_lt(lo[i], hi[i], "the regions overlap");
    }
    int differ = 0, shared = 0;
    for (int64_t z = lo[2]; z < hi[2]; z++)
        for (int64_t y = lo[1]; y < hi[1]; y++)
            for (int64_t x = lo[0]; x < hi[0]; x++) {
                float va = field_value(&a, (int)(x - a_desc->first[0]), (int)(y - a_desc->first[1]), (int)(z - a_desc->first[2]));
                float vb = field_value(&b, (int)(x - b_desc->first[0]), (int)(y - b_desc->first[1]), (int)(z - b_desc->first[2]));
                differ += memcmp(&va, &vb, sizeof va) != 0;
                shared++;
            }
    cr_expect_eq(differ, 0, "%d of %d shared samples differ (sigma %g)", differ, shared, (double)a_desc->sigma);
    terrain_field_free(&a);
    terrain_field_free(&b);
}

Test(terrain_field, adjacent_regions_agree_exactly) {
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(11) });
    int64_t y = surface_height(world, 1, 0) - 16;
    const float sigmas[] = { 1.0f, 1.37f, 0.8f, 2.5f };
    for (size_t s = 0; s < CORE_COUNTOF(sigmas); s++) {
        float sigma = sigmas[s];
        /* Two chunk-sized regions sharing the face x = 32, and one sharing the face z = 0. */
        terrain_field_desc a = { .first = { 0, y, 0 }, .size = { 33, 33, 33 }, .sigma = sigma };
        terrain_field_desc b = { .first = { 32, y, 0 }, .size = { 33, 33, 33 }, .sigma = sigma };
        terrain_field_desc c = { .first = { 0, y, -32 }, .size = { 33, 33, 33 }, .sigma = sigma };
        /* A region of another shape and offset overlapping both. */
        terrain_field_desc d = { .first = { 13, y + 5, -7 }, .size = { 41, 20, 19 }, .sigma = sigma };
        expect_shared_samples_identical(world, &a, &b);
        expect_shared_samples_identical(world, &a, &c);
        expect_shared_samples_identical(world, &a, &d);
        expect_shared_samples_identical(world, &b, &d);
    }
    terrain_world_destroy(world);
}

Test(terrain_field, far_from_the_origin) {
    /* Chunk coordinates in the millions: the same terrain shape (flat), the same values. */
    hand_world hand = { .column = flat_column, .ground = 10.0 };
    terrain_world *world = hand_world_create(&hand);
    terrain_field near, far;
    cr_assert(terrain_field_sample(world, &(terrain_field_desc){ .first = { 0, 5, 0 }, .size = { 4, 11, 4 } }, &near));
    cr_assert(terrain_field_sample(world, &(terrain_field_desc){ .first = { -100000000, 5, 3000000000LL }, .size = { 4, 11, 4 } }, &far));
    cr_expect_eq(memcmp(near.values, far.values, 4 * 11 * 4 * sizeof(float)), 0);
    cr_expect_float_eq(field_value(&near, 1, 5, 1), 0.0f, 0.0f);   /* y = 10: on the ground */
    terrain_field_free(&near);
    terrain_field_free(&far);
    terrain_world_destroy(world);
}

Test(terrain_field, absurd_requests_are_refused) {
    hand_world hand = { .column = flat_column, .ground = 0.0 };
    terrain_world *world = hand_world_create(&hand);
    terrain_field field;
    cr_expect_not(terrain_field_sample(world, &(terrain_field_desc){ .size = { 0, 4, 4 } }, &field));
    cr_expect_null(field.values);
    cr_expect_not(terrain_field_sample(world, &(terrain_field_desc){ .size = { 4, 1025, 4 } }, &field));
    cr_expect_not(terrain_field_sample(world, &(terrain_field_desc){ .size = { 4, 4, 4 }, .sigma = -1.0f }, &field));
    cr_expect_not(terrain_field_sample(world, &(terrain_field_desc){ .size = { 4, 4, 4 }, .sigma = NAN }, &field));
    cr_expect_not(terrain_field_sample(world, &(terrain_field_desc){ .size = { 4, 4, 4 }, .sigma = 1000.0f }, &field));
    terrain_field_free(&field);   /* harmless on a refused request */
    terrain_world_destroy(world);
}

/* ---- amplification (terrain_world_desc.amplify, 003 §5) ------------------------------------- */

/* A ball of radius 3 in the air at (10, 20, 10): f̃ = max(f, clamp(3 − |p − c|, −1, 1)). */
static void add_ball(void *user, terrain_world *world, terrain_field *field) {
    (void)world;
    int *calls = user;
    (*calls)++;
    for (int z = 0; z < field->nz; z++)
        for (int y = 0; y < field->ny; y++)
            for (int x = 0; x < field->nx; x++) {
                double p[3] = { field->origin[0] + x * field->spacing - 10, field->origin[1] + y * field->spacing - 20,
                                field->origin[2] + z * field->spacing - 10 };
                float ball = fmaxf(-1.0f, fminf(1.0f, (float)(3.0 - sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]))));
                float *v = &field->values[((size_t)z * field->ny + y) * field->nx + x];
                *v = fmaxf(*v, ball);
            }
}

/* Every way the world samples its field sees what the amplifier adds, the base field does not,
 * and samples the amplifier leaves alone are the stacks' own bits. */
Test(terrain_field, amplify_reaches_every_sampler) {
    hand_world hand = { .column = flat_column, .ground = 10.0 };
    int calls = 0;
    terrain_world *plain = hand_world_create(&hand);
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generate = hand_generate, .generate_user = &hand,
                                                                     .amplify = add_ball, .amplify_user = &calls });
    float centre = terrain_field_at(world, 10, 20, 10, 0), base = terrain_field_base_at(world, 10, 20, 10, 0);
    float near_top = terrain_field_at(world, 10, 22.5, 10, 0);
    cr_expect_float_eq(centre, 1.0f, 1e-6f);      /* the ball's centre */
    cr_expect_float_eq(base, -1.0f, 1e-6f);       /* air without it */
    cr_expect_float_eq(near_top, 0.5f, 1e-6f);    /* 0.5 m inside its top */
    cr_assert_eq(calls, 2, "terrain_field_at amplifies, terrain_field_base_at does not: %d calls", calls);
    for (int step = 1; step <= 2; step++) {
        terrain_field a, b;
        terrain_field_desc desc = { .first = { 0, 8, 0 }, .size = { 12, 10, 12 }, .step = step };
        cr_assert(terrain_field_sample(world, &desc, &a));
        cr_assert(terrain_field_sample(plain, &desc, &b));
        int raised = 0;
        for (size_t i = 0; i < (size_t)12 * 10 * 12; i++) {
            if (a.values[i] != b.values[i]) {
                cr_assert_gt(a.values[i], b.values[i]);
                raised++;
            }
        }
        cr_assert_gt(raised, 0, "step %d: the ball is in the samples", step);
        terrain_field_free(&a);
        terrain_field_free(&b);
    }
    /* and the mesh: the chunk holding the ball reaches up to its top, 23 m */
    terrain_mesh mesh;
    cr_assert(terrain_mesh_chunk(world, 0, 0, 0, &(terrain_lod_desc){ 0 }, &mesh));
    float top = -INFINITY;
    for (uint32_t v = 0; v < mesh.vertex_count; v++) top = fmaxf(top, (float)mesh.origin[1] + mesh.vertices[v].position[1]);
    cr_assert_float_eq(top, 23.0f, 0.05f);
    terrain_mesh_free(&mesh);
    terrain_world_destroy(world);
    terrain_world_destroy(plain);
}
