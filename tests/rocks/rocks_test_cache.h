/* rocks_test_cache.h — one build of each small tile set per test run.
 *
 * Criterion runs every test in a process of its own, so each would build its tile set again
 * (seconds under ASan). tools/test sets ROCKS_TEST_CACHE_DIR to a folder it empties at the start
 * of a run; tests then pass this path as the set's cache_path, so the first test builds and the
 * others read. Without the variable (a test run by hand) every test builds its own set. The
 * folder is fresh each run, so a cache never outlives the code that wrote it. */
#ifndef ROCKS_TEST_CACHE_H
#define ROCKS_TEST_CACHE_H

#include <stdio.h>
#include <stdlib.h>

#include "rocks/rocks.h"

static inline const char *rocks_test_cache(const rocks_tileset_desc *desc) {
    static char path[512];
    const char *dir = getenv("ROCKS_TEST_CACHE_DIR");
    if (!dir || !*dir) return NULL;
    snprintf(path, sizeof path, "%s/set-%llu-%d-%d-%d.bin", dir, (unsigned long long)desc->seed, desc->cells,
             desc->voxels_per_cell, (int)desc->shape);
    return path;
}

#endif
