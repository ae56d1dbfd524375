/* Ambient occlusion at mesh time (terrain_vertex.occlusion) and the continuous material weights
 * (000 §6), on worlds made by hand whose answers can be reasoned out without the mesher:
 *
 *   - an infinite flat plane sees the whole sky: openness 1 everywhere;
 *   - the floor of a narrow trench sees a strip of sky: less than the plain;
 *   - the floor of a cave closed on every side sees none of it within reach: less still;
 *   - a vertex on the border of two chunks gets the same bytes from both meshes;
 *   - weights from a sand layer over bedrock, crossed by a slope, rise smoothly (many levels)
 *     and match the exact overlap of a one-metre segment with the layers at hand-picked points. */
#include "../engine/test.h"
#include "core/core.h"
#include "terrain/terrain.h"
#include "terrain/terrain_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---- worlds -------------------------------------------------------------------------------- */

enum { PLAIN_TOP = 10 };

/* Ground at 10.25 m everywhere (not on a slab boundary, on purpose). */
static void plane_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    (void)user, (void)x, (void)z;
    terrain_stacks_builder_push(b, TERRAIN_BEDROCK, 10.25f - TERRAIN_FLOOR_Y);
}

/* Ground at 10 m with a trench 2 m wide (columns 31 and 32, across the border of chunks 0 and 1
 * along x) and 5.75 m deep (its floor at 4.25 m: off the grid's samples, so the floor's vertices
 * on x = 32 belong to both chunks), running along z; and, away from it, a cave closed on every
 * side: columns 44 … 55 × 10 … 21 are bedrock to 1.5 m, air from 1.5 to 5.5 m, bedrock again
 * from 5.5 to 10 m. */
static void trench_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    (void)user;
    if (x == 31 || x == 32) {
        terrain_stacks_builder_push(b, TERRAIN_BEDROCK, 4.25f - TERRAIN_FLOOR_Y);
    } else if (x >= 44 && x <= 55 && z >= 10 && z <= 21) {
        terrain_stacks_builder_push(b, TERRAIN_BEDROCK, 1.5f - TERRAIN_FLOOR_Y);
        terrain_stacks_builder_push(b, TERRAIN_AIR, 4.0f);
        terrain_stacks_builder_push(b, TERRAIN_BEDROCK, 4.5f);
    } else {
        terrain_stacks_builder_push(b, TERRAIN_BEDROCK, (float)PLAIN_TOP - TERRAIN_FLOOR_Y);
    }
}

/* A slope along x, h = 6 + x/16 m, of bedrock under sand from S(z) = 6.5 + (z mod 8)/16 m up
 * (columns whose top is below S are bare bedrock): the boundary crosses the slope obliquely. */
static double slope_top(int64_t x) { return 6.0 + (double)x / 16.0; }
static double sand_base(int64_t z) { return 6.5 + 0.0625 * (double)(((z % 8) + 8) % 8); }
static void slope_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    (void)user;
    double top = slope_top(x), base = sand_base(z);
    if (top <= base) {
        terrain_stacks_builder_push(b, TERRAIN_BEDROCK, (float)(top - TERRAIN_FLOOR_Y));
    } else {
        terrain_stacks_builder_push(b, TERRAIN_BEDROCK, (float)(base - TERRAIN_FLOOR_Y));
        terrain_stacks_builder_push(b, TERRAIN_SAND, (float)(top - base));
    }
}

static terrain_stacks *plane_chunk(void *user, terrain_chunk_coord c) { return terrain_stacks_from_columns(c, plane_column, user); }
static terrain_stacks *trench_chunk(void *user, terrain_chunk_coord c) { return terrain_stacks_from_columns(c, trench_column, user); }
static terrain_stacks *slope_chunk(void *user, terrain_chunk_coord c) { return terrain_stacks_from_columns(c, slope_column, user); }

static terrain_mesh mesh_chunk(terrain_world *world, int64_t cx, int64_t cy, int64_t cz) {
    terrain_mesh mesh;
    cr_assert(terrain_mesh_chunk(world, cx, cy, cz, NULL, &mesh));
    cr_assert_gt(mesh.vertex_count, 0, "chunk (%lld, %lld, %lld) holds the surface", (long long)cx, (long long)cy,
                 (long long)cz);
    return mesh;
}

static double openness(const terrain_vertex *v) { return 1.0 - v->occlusion / 255.0; }

static void world_position(const terrain_mesh *m, uint32_t i, double p[3]) {
    for (int a = 0; a < 3; a++) p[a] = m->origin[a] + m->vertices[i].position[a];
}

/* ---- openness ------------------------------------------------------------------------------ */

Test(terrain_occlusion, an_infinite_plane_is_open) {
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generate = plane_chunk });
    terrain_mesh mesh = mesh_chunk(world, 0, 0, 0);
    int closed = 0;
    for (uint32_t i = 0; i < mesh.vertex_count; i++) closed += openness(&mesh.vertices[i]) < 0.99;
    cr_expect_eq(closed, 0, "%d of %u vertices of a plane are not open", closed, mesh.vertex_count);
    terrain_mesh_free(&mesh);
    terrain_world_destroy(world);
}

Test(terrain_occlusion, without_a_world_everything_is_open) {
    terrain_field field = { .nx = 6, .ny = 6, .nz = 6, .spacing = 1.0f };
    field.values = core_alloc(6 * 6 * 6 * sizeof *field.values);
    for (int i = 0; i < 6 * 6 * 6; i++) field.values[i] = (i / 36) < 3 ? 1.0f : -1.0f;   /* solid below z = 2.5 */
    terrain_mesh mesh;
    cr_assert(terrain_mesh_build(&field, &(terrain_mesh_desc){ 0 }, &mesh));
    cr_assert_gt(mesh.vertex_count, 0);
    for (uint32_t i = 0; i < mesh.vertex_count; i++) {
        cr_expect_eq(mesh.vertices[i].occlusion, 0);
        cr_expect_eq(mesh.vertices[i].reserved[0] | mesh.vertices[i].reserved[1] | mesh.vertices[i].reserved[2], 0);
    }
    terrain_mesh_free(&mesh);
    terrain_field_free(&field);
}

/* The lowest and highest openness among upward-facing vertices within the box (world metres). */
typedef struct openness_range { double lowest, highest; int found; } openness_range;

static openness_range openness_in(const terrain_mesh *m, double x0, double x1, double y0, double y1, double z0,
                                  double z1) {
    openness_range r = { 2.0, -1.0, 0 };
    for (uint32_t i = 0; i < m->vertex_count; i++) {
        double p[3];
        world_position(m, i, p);
        if (p[0] < x0 || p[0] > x1 || p[1] < y0 || p[1] > y1 || p[2] < z0 || p[2] > z1) continue;
        if (m->vertices[i].normal[1] < 0.9f) continue;
        r.found++;
        r.lowest = fmin(r.lowest, openness(&m->vertices[i]));
        r.highest = fmax(r.highest, openness(&m->vertices[i]));
    }
    return r;
}

Test(terrain_occlusion, a_trench_floor_is_darker_than_the_plain_and_a_cave_darker_still) {
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generate = trench_chunk });
    terrain_mesh west = mesh_chunk(world, 0, 0, 0), east = mesh_chunk(world, 1, 0, 0);
    /* The plain, far (> 8 m + the lift) from the trench and the cave: open. */
    openness_range plain_range = openness_in(&west, 4, 18, 9, 11, 4, 28);
    double plain = plain_range.lowest;
    int plain_count = plain_range.found;
    /* The trench floor's middle line (x = 32, where both trench columns meet): the field's
     * surface lies at 4.25 m there. */
    openness_range trench_range = openness_in(&east, 31.9, 32.1, 3, 5, 4, 28);
    double trench = trench_range.highest;
    int trench_count = trench_range.found;
    /* The cave floor (at 1.5 m), away from its walls. */
    openness_range cave_range = openness_in(&east, 47, 52, 1, 2, 13, 18);
    double cave = cave_range.highest;
    int cave_count = cave_range.found;
    cr_assert_gt(plain_count, 0);
    cr_assert_gt(trench_count, 0);
    cr_assert_gt(cave_count, 0);
    cr_expect_geq(plain, 0.99, "the plain: %.3f", plain);
    /* Walls 5.75 m high at 1 m on either side hide everything but the strip along the trench
     * and a cone overhead. */
    cr_expect_lt(trench, 0.75, "the trench: %.3f", trench);
    /* The cave's roof 4 m up covers every ray: less than the trench, whose strip is open. */
    cr_expect_lt(cave, trench, "the cave %.3f, the trench %.3f", cave, trench);
    cr_expect_lt(cave, 0.4, "the cave: %.3f", cave);
    terrain_mesh_free(&west);
    terrain_mesh_free(&east);
    terrain_world_destroy(world);
}

/* Vertices on the plane x = 32 that both chunks mesh (not on a grid sample: a sample with f = 0
 * is reached from both sides, and each chunk meshes only its own side's edges). */
typedef struct border_vertex { double p[3]; uint8_t weights[4], occlusion; } border_vertex;

static int compare_border(const void *a, const void *b) {
    const border_vertex *x = a, *y = b;
    for (int i = 0; i < 3; i++)
        if (x->p[i] != y->p[i]) return x->p[i] < y->p[i] ? -1 : 1;
    return 0;
}

static border_vertex *border_of(const terrain_mesh *m, double plane, size_t *count) {
    border_vertex *out = malloc((m->vertex_count + 1) * sizeof *out);
    *count = 0;
    for (uint32_t i = 0; i < m->vertex_count; i++) {
        border_vertex b;
        world_position(m, i, b.p);
        bool on_sample = b.p[0] == floor(b.p[0]) && b.p[1] == floor(b.p[1]) && b.p[2] == floor(b.p[2]);
        if (b.p[0] != plane || on_sample) continue;
        memcpy(b.weights, m->vertices[i].weights, 4);
        b.occlusion = m->vertices[i].occlusion;
        out[(*count)++] = b;
    }
    qsort(out, *count, sizeof *out, compare_border);
    return out;
}

static void expect_same_border_bytes(const terrain_mesh *a, const terrain_mesh *b, double plane, int *occluded) {
    size_t na, nb;
    border_vertex *va = border_of(a, plane, &na), *vb = border_of(b, plane, &nb);
    cr_assert_gt(na, 0);
    cr_assert_eq(na, nb);
    int differ = 0;
    for (size_t i = 0; i < na; i++) {
        cr_assert_eq(compare_border(&va[i], &vb[i]), 0, "the same border vertices");
        differ += va[i].occlusion != vb[i].occlusion || memcmp(va[i].weights, vb[i].weights, 4) != 0;
        *occluded += va[i].occlusion > 0;
    }
    cr_expect_eq(differ, 0, "%d of %zu border vertices differ in occlusion or weights", differ, na);
    free(va);
    free(vb);
}

Test(terrain_occlusion, border_vertices_agree_in_both_chunks) {
    /* The trench runs along the border x = 32: its walls and floor are on it. */
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generate = trench_chunk });
    terrain_mesh west = mesh_chunk(world, 0, 0, 0), east = mesh_chunk(world, 1, 0, 0);
    int occluded = 0;
    expect_same_border_bytes(&west, &east, 32.0, &occluded);
    cr_expect_gt(occluded, 0, "some border vertices are in the trench's shade");
    terrain_mesh_free(&west);
    terrain_mesh_free(&east);
    terrain_world_destroy(world);

    /* Generated terrain: overhangs, slopes and whatever else the seed puts on the border. */
    world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(5) });
    const terrain_stacks *stacks = terrain_world_stacks(world, (terrain_chunk_coord){ 0, 0 });
    int64_t cy = (int64_t)floor(terrain_stacks_top(stacks, 31, 16) / 32.0);
    west = mesh_chunk(world, 0, cy, 0), east = mesh_chunk(world, 1, cy, 0);
    occluded = 0;
    expect_same_border_bytes(&west, &east, 32.0, &occluded);
    terrain_mesh_free(&west);
    terrain_mesh_free(&east);
    terrain_world_destroy(world);
}

/* ---- weights (000 §6) ---------------------------------------------------------------------- */

static int compare_x(const void *a, const void *b) {
    const double *x = a, *y = b;
    return x[0] < y[0] ? -1 : x[0] > y[0];
}

Test(terrain_occlusion, weights_rise_smoothly_where_sand_meets_bedrock_on_a_slope) {
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generate = slope_chunk });
    terrain_mesh mesh = mesh_chunk(world, 0, 0, 0);
    /* Rows of constant z (whole metres: the vertices on x- and y-edges there), x ascending: the
     * sand's weight never falls going up the slope, and each row takes many values. */
    double (*row)[2] = malloc(mesh.vertex_count * sizeof *row);
    int rows = 0, levels_min = 1 << 30;
    for (int z = 4; z < 28; z += 3) {
        int count = 0;
        for (uint32_t i = 0; i < mesh.vertex_count; i++) {
            double p[3];
            world_position(&mesh, i, p);
            const uint8_t *w = mesh.vertices[i].weights;
            cr_assert_eq(w[0] + w[1] + w[2] + w[3], 255);
            if (p[2] != z || p[0] < 2 || p[0] > 30) continue;
            row[count][0] = p[0], row[count][1] = w[1];
            count++;
        }
        qsort(row, (size_t)count, sizeof *row, compare_x);
        int levels = 0, falls = 0;
        for (int k = 0; k < count; k++) {
            if (k > 0 && row[k][1] < row[k - 1][1]) falls++;
            bool seen = false;
            for (int m = 0; m < k; m++) seen |= row[m][1] == row[k][1];
            levels += !seen;
        }
        cr_expect_eq(falls, 0, "row z = %d: the sand weight falls %d times going up", z, falls);
        levels_min = levels < levels_min ? levels : levels_min;
        rows++;
    }
    cr_expect_gt(rows, 0);
    /* 8 point samples gave at most 9 levels; the sand rises over ~1 m of height, 16 m of x here
     * (from x = 8 … 15 on, by the row's S). */
    cr_expect_gt(levels_min, 9, "every row takes more than 9 distinct sand weights (fewest: %d)", levels_min);
    free(row);
    terrain_mesh_free(&mesh);

    /* By hand, facing up (the segment [y − 1, y], its centre half a metre down; columns' centres
     * at whole metres + ½), at z = 5.5 (column 5 alone: S = 6.5 + 5/16 = 6.8125).
     * x = 40.5: column 40 alone, its top 6 + 40/16 = 8.5. At y = 7.5: [6.5, 7.5] holds bedrock
     * 6.5 … 6.8125 (0.3125) and sand 6.8125 … 7.5 (0.6875): 255·0.3125 = 79.7 → 80,
     * 255·0.6875 = 175.3 → 175. */
    uint8_t w[4];
    const float up[3] = { 0, 1, 0 };
    terrain__mesh_vertex_weights(world, (const double[3]){ 40.5, 7.5, 5.5 }, up, w);
    cr_expect(w[0] == 80 && w[1] == 175 && w[2] == 0 && w[3] == 0, "x = 40.5: %d %d %d %d", w[0], w[1], w[2], w[3]);
    /* x = 40.75: columns 40 (¾) and 41 (¼; top 6 + 41/16 = 8.5625). At y = 8.75, [7.75, 8.75]:
     * column 40 has sand 7.75 … 8.5, column 41 sand 7.75 … 8.5625, no bedrock: all sand, 255.
     * At y = 7.25, [6.25, 7.25]: in both, bedrock 6.25 … 6.8125 (0.5625) and sand 6.8125 … 7.25
     * (0.4375): 143.4 → 143 and 111.6 → 112. */
    terrain__mesh_vertex_weights(world, (const double[3]){ 40.75, 8.75, 5.5 }, up, w);
    cr_expect(w[0] == 0 && w[1] == 255, "x = 40.75, y = 8.75: %d %d", w[0], w[1]);
    terrain__mesh_vertex_weights(world, (const double[3]){ 40.75, 7.25, 5.5 }, up, w);
    cr_expect(w[0] == 143 && w[1] == 112, "x = 40.75, y = 7.25: %d %d", w[0], w[1]);
    /* z = 6.0: columns 5 (½, S = 6.8125) and 6 (½, S = 6.875); x = 40.5, y = 7.5: [6.5, 7.5]
     * holds bedrock 0.3125 and 0.375, sand 0.6875 and 0.625: bedrock 0.34375 and sand 0.65625
     * of the whole: 87.7 → 88 and 167.3 → 167. */
    terrain__mesh_vertex_weights(world, (const double[3]){ 40.5, 7.5, 6.0 }, up, w);
    cr_expect(w[0] == 88 && w[1] == 167, "z = 6: %d %d", w[0], w[1]);
    terrain_world_destroy(world);
}
