/* rocks_test_wall.h — the notched wall that the cliffs' edit tests cut (test_rocks_cliffs_edit.c,
 * test_rocks_threads.c): bedrock up to 20 m for x < 0, a floor at 0 for x ≥ 0 (a face x = 0
 * across z). Notched, columns [NOTCH_X0, 0) × [NOTCH_Z0, NOTCH_Z1) stand only to NOTCH_TOP: a
 * notch 3 m wide and 12 m deep in its top, across the border of column chunks z = 0 and z = 1
 * (z = 32), so cells on either side read it. The generator's user is a const bool: notched. */
#ifndef ROCKS_TEST_WALL_H
#define ROCKS_TEST_WALL_H

#include <stdio.h>
#include <stdlib.h>

#include "rocks/rocks.h"

#define NOTCH_X0 -3
#define NOTCH_Z0 29
#define NOTCH_Z1 35
#define NOTCH_TOP 8.0f

static const bool plain = false, notched = true;

static inline void wall_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *b) {
    const bool *is_notched = user;
    float top = x < 0 ? 20.0f : 0.0f;
    if (*is_notched && x >= NOTCH_X0 && x < 0 && z >= NOTCH_Z0 && z < NOTCH_Z1) top = NOTCH_TOP;
    terrain_stacks_builder_push(b, TERRAIN_BEDROCK, top - TERRAIN_FLOOR_Y);
}

static inline terrain_stacks *wall_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, wall_column, user);
}

/* Cliffs of one columnar stratum on 12 m tiles, or NULL. Under tools/test (ROCKS_TEST_CACHE_DIR,
 * a folder fresh each run) the tile is built once a run, in `folder` there, and read back by
 * every cliffs made after (seconds saved under the sanitizers). */
static inline rocks_cliffs *columnar_cliffs_in(const char *folder) {
    static char dir[512];
    const char *root = getenv("ROCKS_TEST_CACHE_DIR");
    if (root && *root) snprintf(dir, sizeof dir, "%s/%s", root, folder);
    return rocks_cliffs_create(&(rocks_cliffs_desc){ .strata_count = 1, .strata = { ROCKS_BLOCK_COLUMNAR },
                                                     .tile_size = 12, .cache_dir = root && *root ? dir : NULL });
}

#endif
