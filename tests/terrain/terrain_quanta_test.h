/* terrain_quanta_test.h — counting material in the tests that check mass: a layer of t metres is
 * round(32·t) quanta (TERRAIN_HEIGHT_QUANTUM), summed over columns. Brushes add and stabilization
 * moves exact quanta, so these sums are the tests' invariants. */
#ifndef TERRAIN_QUANTA_TEST_H
#define TERRAIN_QUANTA_TEST_H

#include "terrain/terrain.h"

#include <math.h>
#include <stdint.h>

/* Quanta of `material` in the chunk (quanta·column). */
static inline int64_t chunk_quanta(const terrain_stacks *stacks, terrain_material material) {
    int64_t q = 0;
    terrain_layer layers[64];
    for (int k = 0; k < TERRAIN_CHUNK_COLUMNS; k++)
        for (int i = 0; i < TERRAIN_CHUNK_COLUMNS; i++) {
            int n = terrain_stacks_column(stacks, i, k, layers, 64);
            for (int l = 0; l < n && l < 64; l++)
                if (layers[l].material == material) q += llroundf(layers[l].thickness / TERRAIN_HEIGHT_QUANTUM);
        }
    return q;
}

/* Quanta of `material` in chunks x0 … x1 by z0 … z1 of the world. */
static inline int64_t world_quanta(terrain_world *w, int64_t x0, int64_t x1, int64_t z0, int64_t z1,
                                   terrain_material material) {
    int64_t q = 0;
    for (int64_t z = z0; z <= z1; z++)
        for (int64_t x = x0; x <= x1; x++)
            q += chunk_quanta(terrain_world_stacks(w, (terrain_chunk_coord){ x, z }), material);
    return q;
}

#endif
