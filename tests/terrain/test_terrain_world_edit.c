/* Edits in the world (terrain.h, "edits in the world"): tools applied through terrain_world_edit,
 * commits, the change queue, pointers that stay valid, and edits that survive eviction through
 * the log (or by pinning without one). Expectations are worked out from the tools' definitions
 * (a deposit adds exactly its volume, a flat world has a known top) and from invariants. */
#include "../engine/test.h"
#include "terrain/terrain.h"
#include "terrain_quanta_test.h"

#include "core/core.h"

#include <math.h>
#include <string.h>

#define N TERRAIN_CHUNK_COLUMNS
#define QPM 32                              /* quanta per metre */

/* Bedrock from the floor up to y = 0 everywhere. */
static void flat_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    (void)user, (void)x, (void)z;
    terrain_stacks_builder_push(builder, TERRAIN_BEDROCK, -TERRAIN_FLOOR_Y);
}

static terrain_stacks *flat_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, flat_column, user);
}

static terrain_world *flat_world(terrain_edit_log *log) {
    return terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(5),
                                                       .generate = flat_chunk, .edits = log });
}

static bool coords_contain(const terrain_chunk_coord *list, int n, int64_t x, int64_t z) {
    for (int i = 0; i < n; i++)
        if (list[i].x == x && list[i].z == z) return true;
    return false;
}

Test(terrain_world_edit, deposit_across_chunk_corner_adds_exactly_its_volume_to_the_chunks_it_covers) {
    terrain_world *w = flat_world(NULL);
    int64_t sand_before = world_quanta(w, -2, 1, -2, 1, TERRAIN_SAND);
    cr_assert_eq(sand_before, 0);
    terrain_chunk_coord changed[16];
    /* A 5 m disc centred on the corner of chunks (−1, −1) … (0, 0): all four get some. */
    int n = terrain_world_edit(w, &(terrain_edit){ .tool = TERRAIN_EDIT_DEPOSIT,
                                                   .deposit = { .x = 0, .z = 0, .radius = 5, .volume = 40 } },
                               changed, 16);
    cr_assert_eq(n, 4);
    for (int64_t z = -1; z <= 0; z++)
        for (int64_t x = -1; x <= 0; x++) cr_expect(coords_contain(changed, n, x, z), "chunk (%lld, %lld)", (long long)x, (long long)z);
    /* 40 m³ is 40·32 quanta·column, exactly. */
    cr_expect_eq(world_quanta(w, -2, 1, -2, 1, TERRAIN_SAND), 40 * QPM);
    cr_expect_eq(world_quanta(w, -2, 1, -2, 1, TERRAIN_BEDROCK), (int64_t)16 * N * N * 256 * QPM);
    terrain_world_change taken[16];
    cr_expect_eq(terrain_world_take_changes(w, taken, 16), 4);
    /* Sand on ground at y = 0: the materials changed from y = 0 up to the pile's top. */
    for (int i = 0; i < 4; i++) {
        cr_expect_eq(taken[i].y_min, 0.0f);
        cr_expect(taken[i].y_max > 0.0f && taken[i].y_max < 5.0f, "top %g", (double)taken[i].y_max);
        /* Columns whose centres lie within 5 m of the corner: the first or last five of a chunk. */
        for (int a = 0; a < 2; a++) {
            int64_t c = a ? taken[i].coord.z : taken[i].coord.x;
            if (c == 0) cr_expect(taken[i].column_min[a] >= 0 && taken[i].column_max[a] <= 4);
            else cr_expect(taken[i].column_min[a] >= N - 5 && taken[i].column_max[a] <= N - 1);
        }
    }
    cr_expect_eq(terrain_world_take_changes(w, taken, 16), 0, "each change is taken once");
    /* The world's first four commits, one a chunk: stamps 1 to 4, each once. */
    uint32_t stamps = 0;
    for (int i = 0; i < 4; i++) {
        uint32_t v = terrain_world_chunk_version(w, changed[i]);
        cr_expect(v >= 1 && v <= 4, "version %u", v);
        stamps |= 1u << v;
    }
    cr_expect_eq(stamps, 0x1eu, "stamps 1, 2, 3 and 4");
    cr_expect_eq(terrain_world_chunk_version(w, (terrain_chunk_coord){ 1, 1 }), 0);
    /* The commit count is the newest version: while it holds, no version has changed. */
    cr_expect_eq(terrain_world_commit_count(w), 4);
    terrain_world_stacks(w, (terrain_chunk_coord){ 3, 3 });
    cr_expect_eq(terrain_world_commit_count(w), 4, "generating a chunk commits nothing");
    terrain_world_destroy(w);
}

Test(terrain_world_edit, a_bad_edit_changes_nothing) {
    terrain_world *w = flat_world(NULL);
    terrain_chunk_coord changed[4];
    cr_expect_eq(terrain_world_edit(w, &(terrain_edit){ .tool = TERRAIN_EDIT_DEPOSIT,
                                                        .deposit = { .x = 0, .z = 0, .radius = -1, .volume = 4 } },
                                    changed, 4), -1);
    cr_expect_eq(terrain_world_edit(w, &(terrain_edit){ .tool = TERRAIN_EDIT_SCULPT_ADD,
                                                        .sculpt = { .target = { NAN, 0, 0 }, .radius = 2 } },
                                    changed, 4), -1);
    cr_expect_eq(terrain_world_edit(w, &(terrain_edit){ .tool = TERRAIN_EDIT_STABILIZE }, changed, 4), -1);
    cr_expect_eq(terrain_world_edit(w, &(terrain_edit){ .tool = TERRAIN_EDIT_DEPOSIT,
                                                        .deposit = { .x = 0, .z = 0, .radius = 1000, .volume = 4 } },
                                    changed, 4), -1, "a brush wider than 8 × 8 chunks is refused");
    cr_expect_eq(terrain_world_edit(w, NULL, changed, 4), -1);
    terrain_world_change none[4];
    cr_expect_eq(terrain_world_take_changes(w, none, 4), 0);
    terrain_world_destroy(w);
}

Test(terrain_world_edit, old_stacks_stay_readable_until_the_next_trim) {
    terrain_world *w = flat_world(NULL);
    terrain_chunk_coord c = { 3, -2 };
    const terrain_stacks *before = terrain_world_stacks(w, c);
    uint64_t hash_before = terrain_stacks_hash(before);
    terrain_world_edit(w, &(terrain_edit){ .tool = TERRAIN_EDIT_DEPOSIT,
                                           .deposit = { .x = 3 * N + 16, .z = -2 * N + 16, .radius = 3, .volume = 5 } },
                       NULL, 0);
    const terrain_stacks *after = terrain_world_stacks(w, c);
    cr_assert_neq(after, before);
    /* A job of this frame may still read the old stacks: they must be intact (ASan checks). */
    cr_expect_eq(terrain_stacks_hash(before), hash_before);
    cr_expect_neq(terrain_stacks_hash(after), hash_before);
    uint64_t token = terrain_world_read_begin(w);
    terrain_world_trim(w);
    cr_expect_eq(terrain_stacks_hash(after), terrain_stacks_hash(terrain_world_stacks(w, c)));
    terrain_world_read_end(w, token);
    terrain_world_destroy(w);
}

Test(terrain_world_edit, without_a_log_an_edited_chunk_is_never_evicted) {
    terrain_world *w = flat_world(NULL);
    terrain_world_set_max_chunks(w, 1);
    terrain_world_edit(w, &(terrain_edit){ .tool = TERRAIN_EDIT_DEPOSIT,
                                           .deposit = { .x = 16, .z = 16, .radius = 3, .volume = 5 } },
                       NULL, 0);
    uint64_t edited = terrain_stacks_hash(terrain_world_stacks(w, (terrain_chunk_coord){ 0, 0 }));
    for (int64_t x = 1; x < 6; x++) terrain_world_stacks(w, (terrain_chunk_coord){ x, 0 });
    terrain_world_trim(w);
    cr_expect(terrain_world_has(w, (terrain_chunk_coord){ 0, 0 }), "the edited chunk stays");
    cr_expect_eq(terrain_stacks_hash(terrain_world_stacks(w, (terrain_chunk_coord){ 0, 0 })), edited);
    terrain_world_destroy(w);
}

Test(terrain_world_edit, with_a_log_an_evicted_chunk_comes_back_byte_for_byte) {
    terrain_edit_log *log = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = terrain_generation_key(&(terrain_generation_desc){ 0 }) });
    terrain_world *w = flat_world(log);
    terrain_world_set_max_chunks(w, 1);
    /* Two strokes on chunk (0, 0): a deposit and an erosion through it. */
    terrain_world_edit(w, &(terrain_edit){ .tool = TERRAIN_EDIT_DEPOSIT,
                                           .deposit = { .material = TERRAIN_BRUSH_ROCKS, .x = 10, .z = 12, .radius = 4,
                                                        .volume = 9 } }, NULL, 0);
    terrain_world_edit(w, &(terrain_edit){ .tool = TERRAIN_EDIT_ERODE,
                                           .erode = { .x = 20, .y = 0, .z = 20, .radius = 3, .depth = 1,
                                                      .rocks_ratio = 0.5f } }, NULL, 0);
    const terrain_stacks *edited = terrain_world_stacks(w, (terrain_chunk_coord){ 0, 0 });
    uint32_t version = terrain_world_chunk_version(w, (terrain_chunk_coord){ 0, 0 });
    cr_expect_geq(version, 2, "two strokes committed it");
    uint64_t hash = terrain_stacks_hash(edited);
    size_t bytes = terrain_stacks_bytes(edited);
    cr_expect_eq(terrain_edit_log_entries(log, (terrain_chunk_coord){ 0, 0 }), 2);
    for (int64_t x = 1; x < 6; x++) terrain_world_stacks(w, (terrain_chunk_coord){ x, 0 });
    terrain_world_trim(w);
    cr_assert(!terrain_world_has(w, (terrain_chunk_coord){ 0, 0 }), "evicted: the log keeps its edits");
    cr_expect_eq(terrain_world_chunk_version(w, (terrain_chunk_coord){ 0, 0 }), version, "evicted, the version kept");
    const terrain_stacks *again = terrain_world_stacks(w, (terrain_chunk_coord){ 0, 0 });
    cr_expect_eq(terrain_stacks_hash(again), hash);
    cr_expect_eq(terrain_stacks_bytes(again), bytes);
    cr_expect_eq(terrain_world_chunk_version(w, (terrain_chunk_coord){ 0, 0 }), version, "the version survives");
    /* A stroke after the eviction gives a version the chunk never had, so a cache keyed on the
     * version (rocks, cliff blocks) sees the change. */
    terrain_world_edit(w, &(terrain_edit){ .tool = TERRAIN_EDIT_DEPOSIT,
                                           .deposit = { .x = 14, .z = 14, .radius = 2, .volume = 1 } }, NULL, 0);
    cr_expect_gt(terrain_world_chunk_version(w, (terrain_chunk_coord){ 0, 0 }), version);
    terrain_world_destroy(w);
    terrain_edit_log_destroy(log);
}

Test(terrain_world_edit, sculpt_through_the_world_raises_the_ground_under_the_target) {
    terrain_world *w = flat_world(NULL);
    terrain_chunk_coord changed[16];
    int n = terrain_world_edit(w, &(terrain_edit){ .tool = TERRAIN_EDIT_SCULPT_ADD,
                                                   .sculpt = { .target = { 16.5, 0, 16.5 }, .radius = 3 } },
                               changed, 16);
    cr_assert_eq(n, 1);
    const terrain_stacks *s = terrain_world_stacks(w, (terrain_chunk_coord){ 0, 0 });
    cr_expect_gt(terrain_stacks_top(s, 16, 16), 0.25f, "material added above y = 0 at the target");
    cr_expect_eq(terrain_stacks_top(s, 2, 2), 0.0f, "columns beyond the ball keep their top");
    n = terrain_world_edit(w, &(terrain_edit){ .tool = TERRAIN_EDIT_SCULPT_CARVE,
                                               .sculpt = { .target = { 8.5, 0, 8.5 }, .radius = 3 } },
                           changed, 16);
    cr_assert_eq(n, 1);
    cr_expect_lt(terrain_stacks_top(terrain_world_stacks(w, (terrain_chunk_coord){ 0, 0 }), 8, 8), -0.25f,
                 "a carve digs below y = 0");
    terrain_world_destroy(w);
}

Test(terrain_world_edit, a_sweep_across_chunks_changes_the_chunks_on_its_way) {
    terrain_world *w = flat_world(NULL);
    double points[2][3] = { { 4, -10, 4 }, { 60, -10, 4 } };
    terrain_chunk_coord changed[16];
    int n = terrain_world_edit(w, &(terrain_edit){ .tool = TERRAIN_EDIT_SWEEP,
                                                   .sweep = { .points = (const double (*)[3])points,
                                                              .point_count = 2, .radius = 2 } },
                               changed, 16);
    cr_expect_eq(n, 2);
    cr_expect(coords_contain(changed, n, 0, 0) && coords_contain(changed, n, 1, 0));
    cr_expect_eq(terrain_world_material_at(w, 32.5, -10, 4.5), TERRAIN_AIR, "the tunnel's axis is air");
    cr_expect_eq(terrain_world_material_at(w, 32.5, -6, 4.5), TERRAIN_BEDROCK, "its roof holds");
    terrain_world_destroy(w);
}
