/* terrain_water_planes.c — water surfaces of a mesh chunk (terrain.h, "water planes"; 002 §3.4, 004 §4.3).
 *
 * Water is a material layer of the stacks (002 §3.1.1); a column has water on top when its
 * highest non-air layer is water, and that layer's top is a flat water surface. A mesh chunk of
 * level L has 32 × 32 cell columns of 2^L metres; for each, one column of the stacks says whether
 * water lies on top there: the column at the cell's centre while a cell is at most a column
 * chunk wide (so it lies in a column chunk the mesher's samples already read), else the cell's
 * first column (a sample's own column, for the same reason: nothing beyond what meshing reads is
 * generated). Surfaces whose height lies in the chunk's y range [y·32·2^L, (y + 1)·32·2^L) are
 * grouped by height — equal within one height quantum, heights being whole quanta — so the sea
 * is one plane and each lake another, and the groups with the most cells are kept (ties: the
 * higher first), each with the mask of its cells and the lowest ground under it.
 *
 * Cost: one walk over each sampled column's layer words (3–4 words typically) and a cached
 * chunk pointer; bench row terrain.water_planes.chunk32.
 */
#include "terrain/data/terrain_data_internal.h"

#include "core/core.h"

#include <stdlib.h>
#include <string.h>

#define WATER_GROUPS_MAX 64               /* distinct surfaces tracked per chunk before ranking */
#define WATER_LEVEL_MAX 16                /* as terrain_lod_desc.level */

typedef struct water_group {
    int64_t surface;                      /* quanta above TERRAIN_FLOOR_Y */
    int64_t deepest;
    int cells;
    uint32_t rows[TERRAIN_MESH_CELLS];
} water_group;

bool terrain__stacks_water(const terrain_stacks *stacks, int i, int k, int64_t *surface, int64_t *ground) {
    terrain__column_cursor cursor = terrain__stacks_cursor(stacks, i, k);
    terrain__qlayer layer;
    int64_t height = 0, solid_top = 0, wet_top = 0;
    bool water_on_top = false;
    while (terrain__cursor_next(&cursor, &layer)) {
        height += layer.quanta;
        if (layer.material == TERRAIN_AIR) continue;
        water_on_top = layer.material == TERRAIN_WATER;
        if (water_on_top) wet_top = height;
        else solid_top = height;
    }
    if (!water_on_top) return false;
    *surface = wet_top;
    *ground = solid_top;
    return true;
}

static int64_t water_floor_div(int64_t a, int64_t b) {
    return a / b - ((a % b != 0) && ((a < 0) != (b < 0)));
}

static void water_group_add(water_group *groups, int *count, int64_t surface, int64_t ground, int i, int k) {
    water_group *g = NULL;
    for (int n = 0; n < *count && !g; n++)
        if (llabs(groups[n].surface - surface) <= 1) g = &groups[n];
    if (!g) {
        if (*count == WATER_GROUPS_MAX) return;   /* a chunk of 64 distinct surfaces: the rest wait */
        g = &groups[(*count)++];
        memset(g, 0, sizeof *g);
        g->surface = surface;
        g->deepest = ground;
    }
    g->cells++;
    g->rows[k] |= 1u << i;
    if (ground < g->deepest) g->deepest = ground;
}

static int water_group_order(const void *a, const void *b) {
    const water_group *x = a, *y = b;
    if (x->cells != y->cells) return x->cells > y->cells ? -1 : 1;
    return (x->surface < y->surface) - (x->surface > y->surface);
}

/* The column sampled for cell c of a chunk starting at world column `first`, cells `step` wide. */
static int64_t water_cell_column(int64_t first, int64_t step, int c) {
    int64_t offset = step <= TERRAIN_CHUNK_COLUMNS ? step / 2 : 0;
    return first + (int64_t)c * step + offset;
}

int terrain_water_planes_find(terrain_world *world, int64_t x, int64_t y, int64_t z, int level,
                              terrain_water_plane *out, int capacity) {
    const int64_t limit = (int64_t)1 << 30;   /* y·32·2^16 quanta stay well inside 64 bits */
    if (!world || (capacity > 0 && !out) || capacity < 0 || level < 0 || level > WATER_LEVEL_MAX || x < -limit ||
        x > limit || y < -limit || y > limit || z < -limit || z > limit) {
        core_log_error("terrain", "water planes: bad request (chunk %lld, %lld, %lld at level %d, capacity %d)",
                   (long long)x, (long long)y, (long long)z, level, capacity);
        return -1;
    }
    int64_t step = (int64_t)1 << level, size = TERRAIN_MESH_CELLS * step;
    /* The chunk's y range in quanta above the floor. */
    int64_t y_lo = (y * size - (int64_t)TERRAIN_FLOOR_Y) * TERRAIN__QUANTA_PER_METRE;
    int64_t y_hi = y_lo + size * TERRAIN__QUANTA_PER_METRE;
    water_group *groups = core_alloc(WATER_GROUPS_MAX * sizeof *groups);
    int count = 0;
    const terrain_stacks *stacks = NULL;
    terrain_chunk_coord cached = { 0, 0 };
    for (int k = 0; k < TERRAIN_MESH_CELLS; k++) {
        int64_t column_z = water_cell_column(z * size, step, k);
        int64_t chunk_z = water_floor_div(column_z, TERRAIN_CHUNK_COLUMNS);
        for (int i = 0; i < TERRAIN_MESH_CELLS; i++) {
            int64_t column_x = water_cell_column(x * size, step, i);
            int64_t chunk_x = water_floor_div(column_x, TERRAIN_CHUNK_COLUMNS);
            if (!stacks || cached.x != chunk_x || cached.z != chunk_z) {
                cached = (terrain_chunk_coord){ chunk_x, chunk_z };
                stacks = terrain_world_stacks(world, cached);
            }
            int64_t surface, ground;
            if (!terrain__stacks_water(stacks, (int)(column_x - chunk_x * TERRAIN_CHUNK_COLUMNS),
                                       (int)(column_z - chunk_z * TERRAIN_CHUNK_COLUMNS), &surface, &ground))
                continue;
            if (surface < y_lo || surface >= y_hi) continue;
            water_group_add(groups, &count, surface, ground, i, k);
        }
    }
    qsort(groups, (size_t)count, sizeof *groups, water_group_order);
    int kept = CORE_MIN(CORE_MIN(count, capacity), TERRAIN_WATER_PLANES_MAX);
    for (int n = 0; n < kept; n++) {
        out[n].height = TERRAIN_FLOOR_Y + (float)groups[n].surface * TERRAIN_HEIGHT_QUANTUM;
        out[n].deepest = TERRAIN_FLOOR_Y + (float)groups[n].deepest * TERRAIN_HEIGHT_QUANTUM;
        memcpy(out[n].rows, groups[n].rows, sizeof out[n].rows);
    }
    core_free(groups, WATER_GROUPS_MAX * sizeof *groups);
    return kept;
}

WaterPlane *terrain__water_find(terrain_world *world, int64_t x, int64_t y, int64_t z, int level) {
    terrain_water_plane planes[TERRAIN_WATER_PLANES_MAX];
    int count = terrain_water_planes_find(world, x, y, z, level, planes, TERRAIN_WATER_PLANES_MAX);
    if (count <= 0) return NULL;
    WaterPlane *water = core_calloc(1, sizeof *water);
    double size = (double)TERRAIN_MESH_CELLS * (double)((int64_t)1 << level);
    water->origin[0] = (double)x * size;
    water->origin[1] = (double)y * size;
    water->origin[2] = (double)z * size;
    water->cell = (float)((int64_t)1 << level);
    water->count = count;
    memcpy(water->planes, planes, (size_t)count * sizeof *planes);
    return water;
}

void terrain__water_free(WaterPlane **water) {
    if (*water) core_free(*water, sizeof **water);
    *water = NULL;
}
