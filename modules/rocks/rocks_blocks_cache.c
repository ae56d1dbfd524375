/* rocks_blocks_cache.c — a block tile's cache file (paper 003 cliff blocks; rocks_block_tile_desc
 * .cache_path), made like the tile set's (rocks_cache.c).
 *
 * Layout (host byte order, checked by a marker; nothing written has padding):
 *     "ROCKBLCK"  u32 version (ROCKS__BLOCK_CACHE_VERSION)  u32 0x01020304
 *     the desc with its defaults filled: u64 seed, i32 type, f32 size, point_spacing,
 *     fracture_spacing, fracture_radius, rounding, joint, relief, relief_scale
 *     u32 counts: blocks, planes, points, discs, grid entries, sample_count;  i32 grid
 *     blocks[blocks]        rocks_block (5 × u32, 9 × f32)
 *     planes[planes]        4 × f32
 *     points[points]        3 × f32
 *     discs[discs]          rocks_block_disc (7 × f32)
 *     grid_first[grid³ + 1] u32
 *     grid_entries[entries] u32 (block << 5 | image)
 *     u64 checksum: core_hash_bytes of every byte before it (ROCKS__BLOCK_CACHE_CHECKSUM_SEED)
 * Tiles with custom blocks are never written (their fields are function pointers). Written to a
 * temporary beside the target and renamed over it. A reader that finds the file missing, cut
 * short, longer than its counts say, of another version, byte order or parameters, damaged
 * (checksum) or inconsistent says which and returns false; rocks_block_tile_create then
 * rebuilds, rewrites and prints one notice.
 *
 * Consistent: every block's plane and point range inside its array and custom = 0; the grid
 * the size build_grid makes for the desc's s; grid_first non-decreasing from 0 to the entry
 * count; every entry's block < block_count and image < 27; every float (anchors, bounds, planes,
 * points, discs) finite and within 16 s of the tile (a built tile's stay within about 3 s);
 * points ≤ samples. So a file whose checksum matches still never makes the reader, or
 * rocks_block_tile_field and the amplifiers on the tile it gives, read outside an array or
 * convert a float out of an integer's range.
 */
#include "rocks_internal.h"

#include "core/core.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#define MAGIC "ROCKBLCK"
#define ENDIAN_MARK 0x01020304u
#define COORDINATE_LIMIT 16.0f        /* tile sides: a built tile's values stay within ~3 s */

typedef struct block_cache_header {
    char magic[8];
    uint32_t version, endian;
    uint64_t seed;
    int32_t type;
    float size, point_spacing, fracture_spacing, fracture_radius, rounding, joint, relief, relief_scale;
    uint32_t blocks, planes, points, discs, grid_entries, sample_count;
    int32_t grid;
} block_cache_header;
_Static_assert(sizeof(block_cache_header) == 8 + 8 + 8 + 4 + 8 * 4 + 6 * 4 + 4, "no padding in the cache header");
_Static_assert(offsetof(block_cache_header, seed) == 16, "the parameters start after magic, version and marker");
_Static_assert(sizeof(rocks_block) == 5 * sizeof(uint32_t) + 9 * sizeof(float), "no padding in a block");
_Static_assert(sizeof(rocks_block_disc) == 7 * sizeof(float), "no padding in a disc");
_Static_assert(sizeof(float[4]) == 16 && sizeof(float[3]) == 12, "planes and points are packed floats");

/* The header of the tile of desc `d` (defaults filled), counts zero. */
static block_cache_header header_of(const rocks_block_tile_desc *d) {
    block_cache_header h;
    memset(&h, 0, sizeof h);
    memcpy(h.magic, MAGIC, 8);
    h.version = ROCKS__BLOCK_CACHE_VERSION;
    h.endian = ENDIAN_MARK;
    h.seed = d->seed;
    h.type = (int32_t)d->type;
    h.size = d->size, h.point_spacing = d->point_spacing, h.fracture_spacing = d->fracture_spacing;
    h.fracture_radius = d->fracture_radius, h.rounding = d->rounding, h.joint = d->joint;
    h.relief = d->relief, h.relief_scale = d->relief_scale;
    return h;
}

/* The arrays in file order: where the pointer is, the item size, the count. */
typedef struct section {
    void **data;
    size_t item;
    uint64_t count;
    uint64_t spare;                   /* items allocated past the count (as the builder does) */
} section;

enum { SECTIONS = 6 };

static void sections(rocks_block_tile *t, section out[SECTIONS]) {
    uint64_t cells = (uint64_t)t->grid * (uint64_t)t->grid * (uint64_t)t->grid;
    section list[SECTIONS] = {
        { (void **)&t->blocks, sizeof *t->blocks, t->block_count, 1 },
        { (void **)&t->planes, sizeof *t->planes, t->plane_count, 1 },
        { (void **)&t->points, sizeof *t->points, t->point_count, 1 },
        { (void **)&t->discs, sizeof *t->discs, t->disc_count, 1 },
        { (void **)&t->grid_first, sizeof *t->grid_first, cells + 1, 0 },
        { (void **)&t->grid_entries, sizeof *t->grid_entries, t->grid_entry_count, 1 },
    };
    memcpy(out, list, sizeof list);
}

bool rocks__block_cache_write(const char *path, const rocks_block_tile *tile_in) {
    rocks_block_tile *tile = (rocks_block_tile *)tile_in;   /* read only; sections() wants pointers */
    block_cache_header h = header_of(&tile->desc);
    h.blocks = tile->block_count, h.planes = tile->plane_count, h.points = tile->point_count;
    h.discs = tile->disc_count, h.grid_entries = tile->grid_entry_count, h.sample_count = tile->sample_count;
    h.grid = tile->grid;

    /* The whole file in memory first: one checksum over exactly the bytes the reader checks. */
    section list[SECTIONS];
    sections(tile, list);
    size_t size = sizeof h + sizeof(uint64_t);
    for (int i = 0; i < SECTIONS; i++) size += list[i].item * list[i].count;
    unsigned char *data = core_alloc(size);
    size_t at = 0;
    memcpy(data + at, &h, sizeof h), at += sizeof h;
    for (int i = 0; i < SECTIONS; i++) {
        size_t bytes = list[i].item * list[i].count;
        if (bytes) memcpy(data + at, *list[i].data, bytes);
        at += bytes;
    }
    uint64_t sum = core_hash_bytes(data, at, ROCKS__BLOCK_CACHE_CHECKSUM_SEED);
    memcpy(data + at, &sum, sizeof sum);

    bool ok = rocks__file_store(path, data, size, "block tile cache");
    core_free(data, size);
    return ok;
}

bool rocks__block_cache_read(const char *path, const rocks_block_tile_desc *desc, rocks_block_tile *tile,
                             const char **why) {
    unsigned char *data;
    size_t size;
    if (!rocks__file_load(path, &data, &size, why)) return false;
    bool parsed = rocks__block_cache_parse(data, size, desc, tile, why);
    core_free(data, size ? size : 1);
    return parsed;
}

static bool finite_near(const float *values, size_t count, float limit) {
    for (size_t i = 0; i < count; i++)
        if (!(fabsf(values[i]) <= limit)) return false;   /* NaN fails too */
    return true;
}

/* Every index inside its array, every float a finite value near the tile (the file's comment). */
static bool consistent(const rocks_block_tile *t) {
    const float s = t->desc.size, limit = COORDINATE_LIMIT * s;
    if (t->point_count > t->sample_count) return false;
    for (uint32_t i = 0; i < t->block_count; i++) {
        const rocks_block *b = &t->blocks[i];
        if (b->custom != 0) return false;
        if ((uint64_t)b->plane_first + b->plane_count > t->plane_count) return false;
        if ((uint64_t)b->point_first + b->point_count > t->point_count) return false;
        if (!finite_near(b->anchor, 3, limit) || !finite_near(b->bounds_min, 3, limit) ||
            !finite_near(b->bounds_max, 3, limit))
            return false;
    }
    if (!finite_near(&t->planes[0][0], (size_t)t->plane_count * 4, limit)) return false;
    if (!finite_near(&t->points[0][0], (size_t)t->point_count * 3, limit)) return false;
    for (uint32_t i = 0; i < t->disc_count; i++)
        if (!finite_near(t->discs[i].centre, 3, limit) || !finite_near(t->discs[i].normal, 3, 2.0f) ||
            !finite_near(&t->discs[i].radius, 1, limit))
            return false;
    const size_t cells = (size_t)t->grid * t->grid * t->grid;
    if (t->grid_first[0] != 0 || t->grid_first[cells] != t->grid_entry_count) return false;
    for (size_t c = 0; c < cells; c++)
        if (t->grid_first[c] > t->grid_first[c + 1]) return false;
    for (uint32_t e = 0; e < t->grid_entry_count; e++)
        if ((t->grid_entries[e] >> 5) >= t->block_count || (t->grid_entries[e] & 31) >= 27) return false;
    return true;
}

/* Leaves the tile as the reader found it on failure: its desc, nothing allocated. */
static bool refuse(rocks_block_tile *t, const rocks_block_tile_desc *desc, const char *reason, const char **why) {
    rocks__block_tile_free_arrays(t);
    memset(t, 0, sizeof *t);
    t->desc = *desc;
    *why = reason;
    return false;
}

bool rocks__block_cache_parse(const unsigned char *data, size_t size, const rocks_block_tile_desc *desc,
                              rocks_block_tile *t, const char **why) {
    block_cache_header want = header_of(desc), h;
    memset(t, 0, sizeof *t);
    t->desc = *desc;
    if (desc->custom_count) return refuse(t, desc, "a tile with custom blocks is never cached", why);
    if (size < sizeof h + sizeof(uint64_t)) return refuse(t, desc, "cut short", why);
    memcpy(&h, data, sizeof h);
    if (memcmp(h.magic, MAGIC, 8) != 0) return refuse(t, desc, "not a block tile cache", why);
    if (h.version != ROCKS__BLOCK_CACHE_VERSION) return refuse(t, desc, "another format version", why);
    if (h.endian != ENDIAN_MARK) return refuse(t, desc, "written on a machine of another byte order", why);
    if (memcmp((const char *)&h + 16, (const char *)&want + 16, offsetof(block_cache_header, blocks) - 16) != 0)
        return refuse(t, desc, "written for other parameters", why);
    /* the grid before its array's size follows from it: what build_grid makes for this s */
    if (h.grid != rocks__block_grid_cells(desc->size)) return refuse(t, desc, "inconsistent (grid)", why);
    t->block_count = h.blocks, t->plane_count = h.planes, t->point_count = h.points;
    t->disc_count = h.discs, t->grid_entry_count = h.grid_entries, t->sample_count = h.sample_count;
    t->grid = h.grid;
    section list[SECTIONS];
    sections(t, list);
    uint64_t expected = sizeof h + sizeof(uint64_t);
    for (int i = 0; i < SECTIONS; i++) expected += (uint64_t)list[i].item * list[i].count;
    /* the size the counts imply before any array is read (nothing is allocated yet) */
    if (expected != size) return refuse(t, desc, expected > size ? "cut short" : "longer than its counts say", why);
    uint64_t stored;
    memcpy(&stored, data + size - sizeof stored, sizeof stored);
    if (core_hash_bytes(data, size - sizeof stored, ROCKS__BLOCK_CACHE_CHECKSUM_SEED) != stored)
        return refuse(t, desc, "damaged (checksum)", why);
    /* each array allocated as the builder leaves it, so destroy frees either alike */
    size_t at = sizeof h;
    for (int i = 0; i < SECTIONS; i++) {
        size_t bytes = list[i].item * list[i].count, spare = list[i].item * list[i].spare;
        *list[i].data = core_alloc(bytes + spare);
        if (bytes) memcpy(*list[i].data, data + at, bytes);
        if (spare) memset((char *)*list[i].data + bytes, 0, spare);
        at += bytes;
    }
    if (!consistent(t)) return refuse(t, desc, "inconsistent", why);
    *why = NULL;
    return true;
}
