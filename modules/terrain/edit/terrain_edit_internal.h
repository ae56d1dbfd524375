/* terrain_edit_internal.h — the private declarations of the terrain's editing area
 * (modules/terrain/edit/): the column region's layout, the stabilizer's bookkeeping, the
 * sculptor's snapshot of the field. The public API is edit/terrain_edit.h.
 *
 * Sections are owned by whoever wrote them; add new declarations in a section of your own.
 */
#ifndef TERRAIN_EDIT_INTERNAL_H
#define TERRAIN_EDIT_INTERNAL_H

#include "terrain/edit/terrain_edit.h"
#include "terrain/data/terrain_data_internal.h"

#include "core/core.h"

#include <stdint.h>

/* ==== editing: columns, stabilization, brushes (terrain_columns.c, terrain_stabilize.c,
 * terrain_brush.c) ============================================================================ */

/* A layer in quanta, as a terrain_columns region keeps it. */
typedef struct terrain__clayer {
    uint32_t material;
    int32_t quanta;
} terrain__clayer;

/* Column flags (terrain_columns.flags). */
#define TERRAIN__COLUMN_UNSORTED 1u   /* layers not in 000 §3.4's order: stabilize sorts them first */
#define TERRAIN__COLUMN_EDITED 2u     /* content changed since terrain_columns_changed_chunks cleared */

/* Heights in the halo of a region side with no neighbour: so high that nothing flows there and
 * no excess points that way (a wall). Real columns stay below TERRAIN__COLUMN_MAX_QUANTA
 * (data/terrain_data_internal.h). */
#define TERRAIN__WALL_HEIGHT (1 << 30)
#define TERRAIN__MAX_SIDE 4096
#define TERRAIN__MAX_REGION_COLUMNS (1 << 22)
#define TERRAIN__FLOW_MAX 65535       /* the largest step, in quanta (2 048 m) */

/* A span of columns [lo, hi] of one row and the last pass that widened it. */
typedef struct terrain__span {
    int32_t lo, hi;
    uint32_t clock;
} terrain__span;

/* The eight neighbour directions, (dx, dz) with d and 7 − d opposite. */
extern const int8_t terrain__dir[8][2];

/* Stabilization runs in passes, one per colour of a 3 × 3 pattern of columns (terrain_stabilize.c);
 * nine passes look at every column once. Clocks count passes and start here, so that "changed in
 * the last nine passes" never wraps below zero. */
#define TERRAIN__COLOURS 9
#define TERRAIN__CLOCK_START 16u

/* The mutable region (terrain.h: terrain_columns). Each column is its lower layers (everything
 * up to and including the highest stable layer: bedrock or a custom material) in a pool, and
 * on top the pile that stabilization moves: sand, rocks, water (000 §3.4's order, air above).
 * The pile is kept as heights in quanta above TERRAIN_FLOOR_Y, in arrays with a one-column halo
 * (cell (i, k) is (k + 1)·pitch + i + 1) so the 3 × 3 stencil never tests for borders; the halo
 * holds walls, or copies of the neighbouring region's columns. */
struct terrain_columns {
    int64_t x0, z0;                   /* world column index of column (0, 0) */
    int width, depth, pitch;          /* pitch = width + 2 */
    size_t cells;                     /* (width + 2)·(depth + 2) */
    /* Padded (halo included). */
    int32_t *base;                    /* top of the lower layers: where the pile starts */
    int32_t *sand_top;                /* base + sand */
    int32_t *ground;                  /* sand_top + rocks: the surface rocks flow on */
    uint32_t *changed;                /* the pass that last changed the column (edits: clock) */
    int32_t *gift_sand, *gift_rocks;  /* halo only: given to the neighbour region this pass */
    terrain__span *changed_span;      /* per row, halo rows too (row k at k + 1) */
    uint32_t clock;                   /* passes run */
    uint32_t last_change;             /* the highest `changed` stamp written */
    /* Per row, written by the job of the row during a pass: */
    int64_t *row_moved;               /* quanta its columns gave */
    uint8_t *row_gifts;               /* whether some of it went into the halo */
    /* Unpadded (index k·width + i). */
    int32_t *water;                   /* above the pile */
    uint32_t *lower_start;
    uint16_t *lower_count, *lower_capacity;
    uint8_t *flags;
    terrain__clayer *pool;
    size_t pool_count, pool_capacity, pool_garbage;
    size_t unsorted;                  /* columns flagged TERRAIN__COLUMN_UNSORTED */
    size_t cave_piles;                /* columns flagged TERRAIN__COLUMN_CAVE_PILE */
    /* Set by the stabilizer for the duration of a call. */
    struct terrain_columns *neighbour[8];      /* by direction (terrain__dir); NULL = edge */
    uint8_t edge_sides;                        /* bit d: no neighbour in direction d */
    bool near_edge;                            /* this pass looks at columns by the border */
};

/* Whether a change stamped `stamp` still matters to pass `pass`: the columns around it have not
 * all been looked at since (one pass per colour). */
static inline bool terrain__recent(uint32_t stamp, uint32_t pass) {
    return stamp + TERRAIN__COLOURS >= pass;
}

/* Widens a row's span by column i changed at pass `clock`; a span whose changes no longer matter
 * starts afresh. */
static inline void terrain__span_extend(terrain__span *span, int i, uint32_t clock) {
    if (!terrain__recent(span->clock, clock)) {
        *span = (terrain__span){ i, i, clock };
        return;
    }
    if (i < span->lo) span->lo = i;
    if (i > span->hi) span->hi = i;
    if (clock > span->clock) span->clock = clock;
}

static inline size_t terrain__cell(const terrain_columns *c, int i, int k) {
    return (size_t)(k + 1) * (size_t)c->pitch + (size_t)(i + 1);
}

/* Whether a material holds up what lies on it and never moves (000 §3.4: bedrock is "always
 * considered as stable"; custom materials are treated alike). */
static inline bool terrain__stable_material(uint32_t material) {
    return material == TERRAIN_BEDROCK || material >= TERRAIN_MATERIAL_BUILTIN_COUNT;
}

/* Column (i, k)'s layers bottom-up, adjacent equal materials merged, into *scratch (grown with
 * core_grow); returns the count. */
int terrain__columns_layers(const terrain_columns *c, int i, int k, terrain__clayer **scratch, size_t *capacity);
/* Replaces column (i, k) by `layers` (bottom-up, quanta > 0, adjacent equal materials may
 * repeat): splits off the pile and flags the column unsorted when it is not in order. Does not
 * mark it changed. */
void terrain__columns_store(terrain_columns *c, int i, int k, const terrain__clayer *layers, int count);
/* Marks column (i, k) changed now: it and its neighbours are looked at by the next nine passes,
 * and its chunk is reported by terrain_columns_changed_chunks. */
void terrain__columns_touch(terrain_columns *c, int i, int k);
/* Sorts column (i, k)'s runs (000 §3.4, Figure 6); touches it when that changed anything. */
void terrain__columns_sort(terrain_columns *c, int i, int k, terrain__clayer **scratch, size_t *capacity);
/* Moves the region's clock forward to `clock`; changes the old clock's next nine passes would
 * still have looked at become changes at the new one. */
void terrain__columns_set_clock(terrain_columns *c, uint32_t clock);

/* ==== spaces inside a column: deposits and erosion at a height, flow on cave floors
 * (terrain_columns.c, terrain_brush.c, terrain_stabilize.c) ================================== */

/* Column flag: granular material (sand or rocks) lies in the lower layers, on a floor under a
 * roof (000 §3.4's "material layers located between two stable bedrock layers"). */
#define TERRAIN__COLUMN_CAVE_PILE 4u

/* A space of a column: the run of layers between a stable layer (or the floor of the world) and
 * the next stable layer above it (or the open sky), which 000 §3.4 keeps sorted sand, rocks,
 * water, air. Heights in quanta above TERRAIN_FLOOR_Y. */
typedef struct terrain__gap {
    int first, end;                   /* its layers [first, end) of the column's list; first − 1
                                         is the stable layer it lies on (none when first = 0) */
    int64_t floor, ceiling;           /* ceiling INT64_MAX for the top space (open sky) */
    int64_t amount[4];                /* sand, rocks, water, air (air 0 in the top space) */
} terrain__gap;

static inline bool terrain__gap_open(const terrain__gap *g) { return g->ceiling == INT64_MAX; }

/* The spaces of a column's layer list (terrain__columns_layers), bottom-up, into `gaps` (at most
 * `capacity`); returns how many there are. Spaces of no height (two stable layers touching) are
 * left out; the open top space is always there, last. */
/* How far a sweep reaches from its skeleton, in radii: 1, or more with a profile curve. */
double terrain__sweep_reach_scale(const terrain_sweep_desc *desc);

int terrain__column_gaps(const terrain__clayer *layers, int count, terrain__gap *gaps, int capacity);
/* The space nearest the height (0 when the height lies inside it); ties go to the higher. */
int terrain__gap_nearest(const terrain__gap *gaps, int count, int64_t height);
/* The space that holds the height, or −1 where a stable layer does (or below the floor). */
int terrain__gap_holding(const terrain__gap *gaps, int count, int64_t height);
/* Rewrites the space's contents (amounts given, sorted sand, rocks, water, air) into column
 * (i, k) whose current list is `layers`: layers below and above the space unchanged. Does not
 * mark the column changed. `scratch` is grown for the new list. */
void terrain__columns_rewrite_gap(terrain_columns *c, int i, int k, const terrain__clayer *layers, int count,
                                  const terrain__gap *gap, const int64_t amount[4], terrain__clayer **scratch,
                                  size_t *capacity);
/* Drops `quanta` of sand or rocks into the space of column (i, k) nearest `height` (quanta above
 * the floor): it lands on that space's floor, under its water (which it displaces first) and
 * takes the place of its air; a space under a roof takes no more than its water and air, and
 * the open top space no more than the column's height limit. Returns the quanta placed; marks
 * the column changed when some were. */
int32_t terrain__columns_insert(terrain_columns *c, int i, int k, int64_t height, uint32_t material, int32_t quanta);

/* ==== end of the editing section ========================================================== */

/* ==== sculpting, sweeping, picking (terrain_sculpt.c) ===================================== */

/* The field of 000 §3.3 with σ = one column, computed from a terrain_columns region's own
 * columns: a snapshot of the solid (sand and bedrock) runs of the region's columns
 * [i0, i1) × [k0, k1), so that an edit computes f from the state before it wrote anything.
 * Columns outside the window count as empty (only the implicit bedrock below the floor). */
typedef struct terrain__region_field {
    int64_t x0, z0;                   /* world column index of window column (0, 0) */
    int width, depth;
    uint32_t *first;                  /* per column (k·width + i): its first run; first[n + 1] ends it */
    int32_t (*runs)[2];               /* solid runs [bottom, top) in quanta above the floor, bottom-up */
    size_t run_capacity;
} terrain__region_field;

/* Snapshots the window (clipped to the region); free with terrain__region_field_free. */
void terrain__region_field_init(terrain__region_field *field, const terrain_columns *columns, int i0, int k0, int i1,
                                int k1);
void terrain__region_field_free(terrain__region_field *field);
/* f at the world point (x, y, z): what terrain_field_at(world, x, y, z, 0) gives for a world
 * holding the same columns (to float rounding). */
double terrain__region_field_at(const terrain__region_field *field, double x, double y, double z);

/* ==== end of the sculpting section ======================================================== */

/* ==== edits in the world: the regions' side (terrain_columns.c) ========================== */

/* The sea after edits: terrain__world_sea (data/terrain_data_internal.h) gives the level. */
/* Applies that rule to every column of the region changed since terrain_columns_changed_chunks
 * last cleared (TERRAIN__COLUMN_EDITED); returns how many it changed (terrain_columns.c). */
int terrain__columns_flood(terrain_columns *columns, int32_t sea_quanta);
/* Displacement by stabilization: in the chunk's changed columns, the water on the pile reaches no
 * higher than the water surface the column had in `before` (the chunk as last committed): sand
 * and rocks that slid under water push it out rather than lift it. Returns the columns capped. */
int terrain__columns_cap_water(terrain_columns *columns, terrain_chunk_coord coord, const terrain_stacks *before);

/* ==== end of the edits-in-the-world section ================================================ */

/* ---- brush materials (terrain_brush.c, terrain_sculpt.c) ---- */

/* A desc's brush material as the stored material: DEFAULT is `fallback`; an unknown value is
 * TERRAIN_MATERIAL_MAX (which no tool accepts). */
static inline terrain_material terrain__brush_material(terrain_brush_material material, terrain_material fallback) {
    switch (material) {
    case TERRAIN_BRUSH_DEFAULT: return fallback;
    case TERRAIN_BRUSH_BEDROCK: return TERRAIN_BEDROCK;
    case TERRAIN_BRUSH_SAND: return TERRAIN_SAND;
    case TERRAIN_BRUSH_ROCKS: return TERRAIN_ROCKS;
    }
    return TERRAIN_MATERIAL_MAX;
}

#endif
