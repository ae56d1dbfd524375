/* terrain_columns_test.h — helpers for the tests of columns regions: stabilization
 * (test_terrain_stabilize.c) and the brushes (test_terrain_brush.c): regions made and filled,
 * quanta of a material in a column or a region, a region's hash, generated chunks loaded. */
#ifndef TERRAIN_COLUMNS_TEST_H
#define TERRAIN_COLUMNS_TEST_H

#include "../engine/test.h"
#include "terrain/terrain.h"

#include "core/core.h"
#include "jobs/jobs.h"

#include <math.h>
#include <stdint.h>

#define QPM 32                              /* quanta per metre */

static inline terrain_columns *region(int64_t x, int64_t z, int width, int depth) {
    terrain_columns *c = terrain_columns_create(&(terrain_columns_desc){ .x = x, .z = z, .width = width, .depth = depth });
    cr_assert_not_null(c);
    return c;
}

/* Every column bedrock up to `height` metres above the floor. */
static inline void fill_flat(terrain_columns *c, float height) {
    terrain_columns_desc e = terrain_columns_extent(c);
    terrain_layer bedrock = { TERRAIN_BEDROCK, height };
    for (int k = 0; k < e.depth; k++)
        for (int i = 0; i < e.width; i++) cr_assert(terrain_columns_set(c, i, k, &bedrock, 1));
}

/* Quanta of `material` in column (i, k). */
static inline int64_t column_quanta(const terrain_columns *c, int i, int k, terrain_material material) {
    terrain_layer layers[64];
    int n = terrain_columns_get(c, i, k, layers, 64);
    cr_assert_leq(n, 64);
    int64_t q = 0;
    for (int l = 0; l < n; l++)
        if (layers[l].material == material) q += llroundf(layers[l].thickness * QPM);
    return q;
}

typedef struct masses { int64_t bedrock, sand, rocks, water; } masses;

static inline masses mass_of(const terrain_columns *c) {
    return (masses){ terrain_columns_mass(c, TERRAIN_BEDROCK), terrain_columns_mass(c, TERRAIN_SAND),
                     terrain_columns_mass(c, TERRAIN_ROCKS), terrain_columns_mass(c, TERRAIN_WATER) };
}

static inline void expect_same_mass(masses a, masses b) {
    cr_expect_eq(a.bedrock, b.bedrock, "bedrock %lld != %lld", (long long)a.bedrock, (long long)b.bedrock);
    cr_expect_eq(a.sand, b.sand, "sand %lld != %lld", (long long)a.sand, (long long)b.sand);
    cr_expect_eq(a.rocks, b.rocks, "rocks %lld != %lld", (long long)a.rocks, (long long)b.rocks);
    cr_expect_eq(a.water, b.water, "water %lld != %lld", (long long)a.water, (long long)b.water);
}

/* Hash of every column of a region (its chunks need not be whole). */
static inline uint64_t region_hash(const terrain_columns *c) {
    terrain_columns_desc e = terrain_columns_extent(c);
    uint64_t h = 1;
    terrain_layer layers[64];
    for (int k = 0; k < e.depth; k++)
        for (int i = 0; i < e.width; i++) {
            int n = terrain_columns_get(c, i, k, layers, 64);
            for (int l = 0; l < n && l < 64; l++) {
                h = core_hash_combine(h, (uint64_t)layers[l].material);
                h = core_hash_combine(h, (uint64_t)llroundf(layers[l].thickness * QPM));
            }
            h = core_hash_combine(h, 0xc01u);
        }
    return h;
}

static inline terrain_stabilize_result stabilize(terrain_columns *c, const terrain_stabilize_desc *params, job_system *jobs) {
    terrain_stabilize_result result;
    cr_assert(terrain_stabilize_region(c, params, jobs, &result));
    return result;
}

static inline void load_generated(terrain_columns *c, uint64_t seed) {
    /* Generated chunks: bedrock, caves, sand on gentle slopes, water below the sea. */
    terrain_generation_desc params = terrain_generation_defaults(seed);
    terrain_columns_desc e = terrain_columns_extent(c);
    for (int64_t cz = e.z / TERRAIN_CHUNK_COLUMNS; cz < (e.z + e.depth) / TERRAIN_CHUNK_COLUMNS; cz++)
        for (int64_t cx = e.x / TERRAIN_CHUNK_COLUMNS; cx < (e.x + e.width) / TERRAIN_CHUNK_COLUMNS; cx++) {
            terrain_stacks *s = terrain_generate_chunk(&params, (terrain_chunk_coord){ cx, cz });
            cr_assert(terrain_columns_load(c, (terrain_chunk_coord){ cx, cz }, s));
            terrain_stacks_destroy(s);
        }
}

#endif
