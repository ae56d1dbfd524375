/* fuzz_tile_cache — libFuzzer target for the rock tile set's cache reader (rocks__cache_parse,
 * modules/rocks/rocks_cache.c) and the set it accepts.
 *
 *   tests/fuzz/run.sh 60 fuzz_tile_cache
 * Seed: tests/fuzz/corpus/fuzz_tile_cache/six_rocks.bin (7.3 KB): the first six rocks of the
 * TILE_DESC set below with everything they reach (tile 0 lists them, the other tiles none,
 * contacts to rocks left out made ROCKS_CONTACT_VARIES), as rocks__cache_write writes it; the
 * whole set's file is 2.4 MB, too much to mutate. entry_offset_out_of_range.bin: that file with an
 * entry's offset made −9, which the reader once let through to placement's index (an index out
 * of bounds there); kept as a seed so the case stays covered.
 *
 * Each input is parsed as it is and with its checksum fixed (fuzz_checksum.h). Traps when a
 * result breaks the contract: a failure says why and keeps nothing; a success gives a set whose every index is
 * inside its arrays (checked here again, independently), and laying it out for placement
 * (rocks_place_index_create) and asking each rock's hull reads only what the set holds (ASan
 * watches).
 */
#include "core/core.h"
#include "rocks/rocks.h"
#include "rocks/rocks_internal.h"

#include "fuzz_checksum.h"

#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const unsigned char *bytes, size_t size);

static const rocks_tileset_desc TILE_DESC = {
    .seed = 3, .cells = 4, .voxels_per_cell = 4, .shape = ROCKS_SHAPE_SLAB, .max_seeds_per_cell = 1,
};

static void check_accepted(const rocks__set *full) {
    const rocks_tileset *s = &full->set;
    for (int t = 0; t < 256; t++)
        if ((uint64_t)s->tiles[t].first + s->tiles[t].count > s->entry_count) __builtin_trap();
    for (uint32_t e = 0; e < s->entry_count; e++) {
        if (s->entries[e].rock >= s->rock_count) __builtin_trap();
        for (int a = 0; a < 3; a++)
            if (s->entries[e].offset[a] < -1 || s->entries[e].offset[a] > 1) __builtin_trap();
    }
    for (uint32_t r = 0; r < s->rock_count; r++) {
        const rocks_rock *rock = &s->rocks[r];
        if ((uint64_t)rock->vertex_first + rock->vertex_count > s->vertex_count ||
            (uint64_t)rock->anchor_first + rock->anchor_count > s->anchor_count ||
            (uint64_t)rock->contact_first + rock->contact_count > s->contact_count)
            __builtin_trap();
        for (int l = 0; l < ROCKS_LODS; l++) {
            if ((uint64_t)rock->index_first[l] + rock->index_count[l] > s->index_count) __builtin_trap();
            for (uint32_t i = 0; i < rock->index_count[l]; i++)
                if (s->indices[rock->index_first[l] + i] >= rock->vertex_count) __builtin_trap();
        }
        const float centre[3] = { rock->seed[0], rock->seed[1], rock->seed[2] };
        float normal[3];
        (void)rocks_hull_distance(rock, centre, normal);
    }
    for (uint32_t c = 0; c < s->contact_count; c++)
        if (s->contacts[c].other != ROCKS_CONTACT_VARIES && s->contacts[c].other >= s->rock_count) __builtin_trap();
    rocks_place_index_destroy(rocks_place_index_create(s));
}

static rocks__params params;   /* TILE_DESC's, made once */

static bool parse_and_check(const unsigned char *bytes, size_t size) {
    rocks__set full;
    memset(&full, 0, sizeof full);
    full.params = params;
    const char *why = NULL;
    bool ok = rocks__cache_parse(bytes, size, &params, &full, &why);
    if (ok) {
        check_accepted(&full);
        rocks__set_free_arrays(&full);
    } else {
        const rocks_tileset *s = &full.set;
        if (!why || !*why) __builtin_trap();
        if (s->entries || s->rocks || s->vertices || s->indices || s->anchors || s->contacts || s->rock_count ||
            full.rock_region || full.rock_cell || full.rock_k)
            __builtin_trap();
    }
    return ok;
}

int LLVMFuzzerTestOneInput(const unsigned char *bytes, size_t size) {
    static bool made;
    if (!made) made = rocks__params_make(&TILE_DESC, &params);
    if (!made) __builtin_trap();
    fuzz_with_checksum(bytes, size, ROCKS__CACHE_CHECKSUM_SEED, parse_and_check);
    return 0;
}
