/* fuzz_block_cache — libFuzzer target for the block tiles' cache reader
 * (rocks__block_cache_parse, modules/rocks/rocks_blocks_cache.c) and the tile it accepts.
 *
 *   tests/fuzz/run.sh 60 fuzz_block_cache
 * Seeds: tests/fuzz/corpus/fuzz_block_cache/tiny.bin, the cache file of the tile of TILE_DESC
 * below (a 4 m tabular tile of 5 blocks, 2.8 KB), as rocks_block_tile_create writes it.
 *
 * Each input is parsed as it is and with its checksum fixed (fuzz_checksum.h). Traps when a
 * result breaks the contract: a failure says why and keeps nothing; a success gives a tile whose every index is
 * inside its arrays (checked here again, independently), and evaluating its field at the input's
 * points and each block at its anchor reads only what the tile holds (ASan watches).
 */
#include "core/core.h"
#include "rocks/rocks.h"
#include "rocks/rocks_internal.h"

#include "fuzz_checksum.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const unsigned char *bytes, size_t size);

/* The seed's desc with its defaults filled (rocks_blocks.h: rounding 0.25, joint 0.15, relief
 * 0.08, relief_scale 0.8), as the parser compares it with the file's. */
static const rocks_block_tile_desc TILE_DESC = {
    .type = ROCKS_BLOCK_TABULAR, .seed = 5, .size = 4.0f, .point_spacing = 0.8f, .fracture_spacing = 1.6f,
    .fracture_radius = 0.0f, .rounding = 0.25f, .joint = 0.15f, .relief = 0.08f, .relief_scale = 0.8f,
};

static void check_accepted(const rocks_block_tile *t, const unsigned char *bytes, size_t size) {
    const size_t cells = (size_t)t->grid * t->grid * t->grid;
    if (t->grid < 1 || t->grid > 32 || !t->blocks || !t->planes || !t->points || !t->discs || !t->grid_first ||
        !t->grid_entries)
        __builtin_trap();
    if (t->desc.seed != TILE_DESC.seed || t->desc.size != TILE_DESC.size || t->from_cache) __builtin_trap();
    for (uint32_t b = 0; b < t->block_count; b++) {
        const rocks_block *block = &t->blocks[b];
        if (block->custom || (uint64_t)block->plane_first + block->plane_count > t->plane_count ||
            (uint64_t)block->point_first + block->point_count > t->point_count)
            __builtin_trap();
        float anchor[3];
        memcpy(anchor, block->anchor, sizeof anchor);
        (void)rocks_block_field(t, b, anchor, NULL);
    }
    if (t->grid_first[0] != 0 || t->grid_first[cells] != t->grid_entry_count) __builtin_trap();
    for (size_t c = 0; c < cells; c++)
        if (t->grid_first[c] > t->grid_first[c + 1]) __builtin_trap();
    for (uint32_t e = 0; e < t->grid_entry_count; e++)
        if ((t->grid_entries[e] >> 5) >= t->block_count || (t->grid_entries[e] & 31) >= 27) __builtin_trap();
    /* the field at points the input picks, and at the tile's corners and centre */
    for (int i = 0; i < 8; i++) {
        double p[3];
        for (int a = 0; a < 3; a++) {
            size_t at = ((size_t)i * 3 + (size_t)a) * 4;
            uint32_t v = at + 4 <= size ? (uint32_t)bytes[at] | (uint32_t)bytes[at + 1] << 8 : (uint32_t)(i * 7 + a);
            p[a] = ((double)(v & 0xffff) / 65535.0 - 0.5) * 8.0 * t->desc.size;
        }
        uint32_t block;
        float value = rocks_block_tile_field(t, p, NULL, NULL, &block);
        if (block != UINT32_MAX ? block >= t->block_count : !isinf(value)) __builtin_trap();
    }
    const double centre[3] = { 0.5 * t->desc.size, 0.5 * t->desc.size, 0.5 * t->desc.size }, corner[3] = { 0, 0, 0 };
    (void)rocks_block_tile_field(t, centre, NULL, NULL, NULL);
    (void)rocks_block_tile_field(t, corner, NULL, NULL, NULL);
}

static bool parse_and_check(const unsigned char *bytes, size_t size) {
    rocks_block_tile tile;
    const char *why = NULL;
    bool ok = rocks__block_cache_parse(bytes, size, &TILE_DESC, &tile, &why);
    if (ok) {
        check_accepted(&tile, bytes, size);
        rocks__block_tile_free_arrays(&tile);
    } else {
        if (!why || !*why) __builtin_trap();
        if (tile.blocks || tile.planes || tile.points || tile.discs || tile.grid_first || tile.grid_entries ||
            tile.block_count || tile.grid_entry_count)
            __builtin_trap();
    }
    return ok;
}

int LLVMFuzzerTestOneInput(const unsigned char *bytes, size_t size) {
    fuzz_with_checksum(bytes, size, ROCKS__BLOCK_CACHE_CHECKSUM_SEED, parse_and_check);
    return 0;
}
