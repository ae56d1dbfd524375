/* rocks_cache.c — the tile set's cache file.
 *
 * Layout (host byte order, checked by a marker; every struct has no padding):
 *     "ROCKTILE"  u32 version  u32 0x01020304
 *     the desc with its defaults filled (seed, cells, voxels_per_cell, shape, s, scales, g_max,
 *     a, b, erosion steps and rate)
 *     u32 counts: entries, rocks, vertices, indices, anchors, contacts;  f32 max_radius
 *     tiles[256], entries, rocks, vertices, indices, anchors, contacts, and per rock its region
 *     instance, seed cell and index (u16, 3 × i16, u8)
 *     u64 checksum: core_hash_bytes of every byte before it
 * Written to a temporary beside the target and renamed over it. A reader that finds anything
 * missing, old, for other parameters, cut short, damaged or inconsistent says which and returns
 * false; rocks_tileset_create then rebuilds, rewrites and prints one notice.
 */
#include "rocks_internal.h"

#include "core/core.h"

#include <errno.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define MAGIC "ROCKTILE"
#define ENDIAN_MARK 0x01020304u
#define FILE_MAX ((size_t)1 << 31)

typedef struct cache_header {
    char magic[8];
    uint32_t version, endian;
    uint64_t seed;
    int32_t cells, voxels_per_cell, shape, seeds_max;
    float scale_min[3], scale_max[3], g_max, contact_radius, blend_radius;
    int32_t erosion_steps;
    float erosion_rate;
    uint32_t entries, rocks, vertices, indices, anchors, contacts;
    float max_radius;
    uint32_t reserved[2];
} cache_header;
_Static_assert(sizeof(cache_header) == 8 + 8 + 8 + 16 + 44 + 24 + 4 + 8, "no padding in the cache header");

static cache_header header_of(const rocks__params *params) {
    const rocks_tileset_desc *d = &params->desc;
    cache_header h;
    memset(&h, 0, sizeof h);
    memcpy(h.magic, MAGIC, 8);
    h.version = ROCKS__CACHE_VERSION;
    h.endian = ENDIAN_MARK;
    h.seed = d->seed;
    h.cells = d->cells, h.voxels_per_cell = d->voxels_per_cell, h.shape = (int32_t)d->shape;
    h.seeds_max = d->max_seeds_per_cell;
    memcpy(h.scale_min, d->scale_min, sizeof h.scale_min);
    memcpy(h.scale_max, d->scale_max, sizeof h.scale_max);
    h.g_max = d->g_max, h.contact_radius = d->contact_radius, h.blend_radius = d->blend_radius;
    h.erosion_steps = d->erosion_steps, h.erosion_rate = d->erosion_rate;
    return h;
}

/* The arrays in file order: pointer, item size, count. */
typedef struct section {
    void **data;
    size_t item;
    uint32_t *count;
} section;

static int sections(rocks__set *full, section out[9]) {
    rocks_tileset *s = &full->set;
    section list[9] = {
        { (void **)&s->entries, sizeof *s->entries, &s->entry_count },
        { (void **)&s->rocks, sizeof *s->rocks, &s->rock_count },
        { (void **)&s->vertices, sizeof *s->vertices, &s->vertex_count },
        { (void **)&s->indices, sizeof *s->indices, &s->index_count },
        { (void **)&s->anchors, sizeof *s->anchors, &s->anchor_count },
        { (void **)&s->contacts, sizeof *s->contacts, &s->contact_count },
        { (void **)&full->rock_region, sizeof *full->rock_region, &s->rock_count },
        { (void **)&full->rock_cell, sizeof *full->rock_cell, &s->rock_count },
        { (void **)&full->rock_k, sizeof *full->rock_k, &s->rock_count },
    };
    memcpy(out, list, sizeof list);
    return 9;
}

/* ---- files ------------------------------------------------------------------------------- */

bool rocks__file_load(const char *path, unsigned char **data_out, size_t *size_out, const char **why) {
    *data_out = NULL, *size_out = 0;
    FILE *f = fopen(path, "rb");
    if (!f) {
        *why = errno == ENOENT ? "missing" : "unreadable";
        return false;
    }
    unsigned char *data = NULL;
    size_t size = 0;
    bool ok = fseek(f, 0, SEEK_END) == 0;
    long end = ok ? ftell(f) : -1;
    ok = ok && end >= 0 && (size_t)end <= FILE_MAX && fseek(f, 0, SEEK_SET) == 0;
    if (ok) {
        size = (size_t)end;
        data = core_alloc(size ? size : 1);
        ok = fread(data, 1, size, f) == size;
    }
    fclose(f);
    if (!ok) {
        *why = end > 0 && (size_t)end > FILE_MAX ? "too large" : "unreadable";
        if (data) core_free(data, size ? size : 1);
        return false;
    }
    *data_out = data, *size_out = size;
    return true;
}

bool rocks__file_store(const char *path, const void *data, size_t size, const char *what) {
    static atomic_uint counter;   /* several files of one process may be written at once */
    const char *slash = strrchr(path, '/');
    if (slash && slash != path) {
        char *dir = core_strdup(path);
        dir[slash - path] = 0;
        core_make_dirs(dir);   /* a failure shows as the open's below */
        core_free(dir, strlen(path) + 1);
    }
    size_t temp_size = strlen(path) + 48;
    char *temp = core_alloc(temp_size);
    snprintf(temp, temp_size, "%s.tmp.%ld.%u", path, (long)getpid(), atomic_fetch_add(&counter, 1));
    FILE *f = fopen(temp, "wb");
    bool ok = f != NULL;
    if (ok) {
        ok &= fwrite(data, size, 1, f) == 1;
        ok &= fclose(f) == 0;
    }
    if (ok) ok = rename(temp, path) == 0;
    if (!ok) {
        core_log_error("rocks", "cannot write the %s %s: %s", what, path, strerror(errno));
        remove(temp);
    }
    core_free(temp, temp_size);
    return ok;
}

/* ---- the tile set ---------------------------------------------------------------------------- */

bool rocks__cache_write(const char *path, const rocks__set *full_in) {
    rocks__set *full = (rocks__set *)full_in;   /* read only; sections() wants pointers */
    const rocks_tileset *set = &full->set;
    cache_header h = header_of(&full->params);
    h.entries = set->entry_count, h.rocks = set->rock_count, h.vertices = set->vertex_count;
    h.indices = set->index_count, h.anchors = set->anchor_count, h.contacts = set->contact_count;
    h.max_radius = set->max_radius;

    /* The whole file in memory first: one checksum over exactly the bytes the reader checks. */
    section list[9];
    int count = sections(full, list);
    size_t size = sizeof h + sizeof set->tiles + sizeof(uint64_t);
    for (int i = 0; i < count; i++) size += list[i].item * *list[i].count;
    unsigned char *data = core_alloc(size);
    size_t at = 0;
    memcpy(data + at, &h, sizeof h), at += sizeof h;
    memcpy(data + at, set->tiles, sizeof set->tiles), at += sizeof set->tiles;
    for (int i = 0; i < count; i++) {
        size_t bytes = list[i].item * *list[i].count;
        if (bytes) memcpy(data + at, *list[i].data, bytes);
        at += bytes;
    }
    uint64_t sum = core_hash_bytes(data, at, ROCKS__CACHE_CHECKSUM_SEED);
    memcpy(data + at, &sum, sizeof sum);
    bool ok = rocks__file_store(path, data, size, "tile cache");
    core_free(data, size);
    return ok;
}

/* Every index inside its array: a file whose checksum matches was written by us, but a reader
 * that trusts a file never reads outside what it allocated. */
static bool consistent(const rocks__set *full) {
    const rocks_tileset *s = &full->set;
    for (int t = 0; t < 256; t++)
        if ((uint64_t)s->tiles[t].first + s->tiles[t].count > s->entry_count) return false;
    for (uint32_t e = 0; e < s->entry_count; e++) {
        if (s->entries[e].rock >= s->rock_count) return false;
        for (int a = 0; a < 3; a++)   /* −1 … 1 (rocks.h): placement indexes by the offset */
            if (s->entries[e].offset[a] < -1 || s->entries[e].offset[a] > 1) return false;
    }
    for (uint32_t r = 0; r < s->rock_count; r++) {
        const rocks_rock *rock = &s->rocks[r];
        if ((uint64_t)rock->vertex_first + rock->vertex_count > s->vertex_count) return false;
        if ((uint64_t)rock->anchor_first + rock->anchor_count > s->anchor_count) return false;
        if ((uint64_t)rock->contact_first + rock->contact_count > s->contact_count) return false;
        if (full->rock_region[r] >= ROCKS__REGION_COUNT) return false;
        for (int l = 0; l < ROCKS_LODS; l++) {
            if ((uint64_t)rock->index_first[l] + rock->index_count[l] > s->index_count) return false;
            for (uint32_t i = 0; i < rock->index_count[l]; i++)
                if (s->indices[rock->index_first[l] + i] >= rock->vertex_count) return false;
        }
    }
    for (uint32_t c = 0; c < s->contact_count; c++)
        if (s->contacts[c].other != ROCKS_CONTACT_VARIES && s->contacts[c].other >= s->rock_count) return false;
    return true;
}

bool rocks__cache_read(const char *path, const rocks__params *params, rocks__set *full, const char **why) {
    unsigned char *data;
    size_t size;
    if (!rocks__file_load(path, &data, &size, why)) return false;
    bool parsed = rocks__cache_parse(data, size, params, full, why);
    core_free(data, size ? size : 1);
    return parsed;
}

bool rocks__cache_parse(const unsigned char *data, size_t size, const rocks__params *params, rocks__set *full,
                        const char **why) {
    cache_header want = header_of(params), h;
    *why = NULL;
    if (size < sizeof h + sizeof(uint64_t)) *why = "cut short";
    if (!*why) {
        memcpy(&h, data, sizeof h);
        if (memcmp(h.magic, MAGIC, 8) != 0) *why = "not a rock tile cache";
        else if (h.version != ROCKS__CACHE_VERSION) *why = "another format version";
        else if (h.endian != ENDIAN_MARK) *why = "written on a machine of another byte order";
        else if (memcmp((const char *)&h + 16, (const char *)&want + 16, offsetof(cache_header, entries) - 16) != 0)
            *why = "written for other parameters";
    }
    rocks_tileset *s = &full->set;
    section list[9];
    int count = sections(full, list);
    if (!*why) {
        s->entry_count = h.entries, s->rock_count = h.rocks, s->vertex_count = h.vertices;
        s->index_count = h.indices, s->anchor_count = h.anchors, s->contact_count = h.contacts;
        uint64_t expected = sizeof h + sizeof s->tiles + sizeof(uint64_t);
        for (int i = 0; i < count; i++) expected += (uint64_t)list[i].item * *list[i].count;
        if (expected != size) *why = expected > size ? "cut short" : "longer than its counts say";
    }
    if (!*why) {
        uint64_t sum, stored;
        sum = core_hash_bytes(data, size - sizeof stored, ROCKS__CACHE_CHECKSUM_SEED);
        memcpy(&stored, data + size - sizeof stored, sizeof stored);
        if (sum != stored) *why = "damaged (checksum)";
    }
    if (*why) {
        memset(s, 0, sizeof *s);
        s->desc = params->desc;
        return false;
    }
    size_t at = sizeof h;
    memcpy(s->tiles, data + at, sizeof s->tiles);
    at += sizeof s->tiles;
    for (int i = 0; i < count; i++) {
        size_t bytes = list[i].item * *list[i].count;
        *list[i].data = core_calloc(*list[i].count ? *list[i].count : 1, list[i].item);
        memcpy(*list[i].data, data + at, bytes);
        at += bytes;
    }
    s->max_radius = h.max_radius;
    if (!consistent(full)) {
        rocks__set_free_arrays(full);
        memset(s, 0, sizeof *s);
        s->desc = params->desc;
        *why = "inconsistent";
        return false;
    }
    s->desc = params->desc;
    return true;
}
