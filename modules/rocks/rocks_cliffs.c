/* rocks_cliffs.c — block tiles replicated over a world's steep bedrock walls (paper 003 §5),
 * through the world's amplify hook: a tile per block type the strata use, presence worked out
 * once per tile cell and cached against the versions of the column chunks it read.
 *
 * Why per tile cell. A field of a 64 m chunk (level 1) meets some 40 000 block copies; asking
 * the stacks about each one at every chunk that sees it would cost more than the chunk's own
 * field. A copy's presence is a pure function of its anchor and the stacks around it, so it is
 * asked once per (type, tile cell) and kept: the neighbouring chunks, the levels of detail and
 * the player's collision queries then reuse it.
 */
#include "rocks_internal.h"
#include "rocks_world_internal.h"

#include "core/core.h"

#include "jobs/jobs.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <string.h>

#define CACHE_CAPACITY 65536          /* entries (a power of two); emptied when 3/4 full */
/* Metres past a point that its presence reads: the field's kernel (1 m), its gradient's quarter
 * metre, and a column's width for the columns the kernel's cube meets in part. */
#define PRESENCE_READS 2.25

typedef struct cell_entry {
    uint64_t key;                     /* 0 = empty */
    int64_t cell[3];
    int type;
    uint64_t versions;                /* hash of the versions of the column chunks it read */
    uint32_t commits;                 /* the world's commit count when they were last read */
    float known_above;                /* presence is worked out for the blocks wider than this */
    uint64_t *bits;                   /* present blocks, one bit each (0 for those not worked out) */
} cell_entry;

struct rocks_cliffs {
    rocks_cliffs_desc desc;
    rocks_block_tile *tiles[ROCKS_BLOCK_TYPE_END];     /* by type; NULL for types no stratum uses */
    double margin[ROCKS_BLOCK_TYPE_END];               /* metres past a tile cell its presence reads */
    double margin_max;
    float reach[3];                                    /* rocks_cliffs_reach */
    size_t words[ROCKS_BLOCK_TYPE_END];                /* 64-bit words of a cell's bits */
    uint32_t type_materials[ROCKS_BLOCK_TYPE_END];     /* the materials mapped to each type, a bit each */
    uint32_t mapped;                                   /* the materials with an entry, a bit each */
    bool bedrock_in_strata;                            /* bedrock has none: the strata decide */
    float widest[ROCKS_BLOCK_TYPE_END];                /* its widest block (coarse fields skip a
                                                          type none of whose blocks they show) */
    uint64_t id;                                       /* this one's, never reused: the memo's owner */
    pthread_mutex_t lock;
    cell_entry *cache;
    size_t used;
    rocks_cliffs_stats_info stats;
    /* the hook's own counts, added atomically: a lock a call cost a picking ray's sample more than
       its work */
    uint64_t fields, copies_present, amplify_ns;
};

static bool cliffs_desc_make(const rocks_cliffs_desc *in, rocks_cliffs_desc *d) {
    *d = in ? *in : (rocks_cliffs_desc){ 0 };
    if (!d->seed) d->seed = 1;
    if (d->strata_count == 0) {
        d->strata[0] = ROCKS_BLOCK_TABULAR, d->strata[1] = ROCKS_BLOCK_COLUMNAR;
        d->strata[2] = ROCKS_BLOCK_EQUIDIMENSIONAL;
        d->strata_count = 3;
    }
    if (d->stratum_height == 0) d->stratum_height = 20.0f;
    if (d->tile_size == 0) d->tile_size = 16.0f;
    if (d->joint == 0) d->joint = fminf(0.6f, d->tile_size / 24.0f);   /* at most the points' spacing */
    if (d->max_spacing == 0) d->max_spacing = 4.0f;
    if (d->block_scale == 0) d->block_scale = 1.0f;
    const char *bad = NULL;
    char why[96];
    if (d->strata_count < 1 || d->strata_count > 8) bad = "strata_count (1 … 8)";
    for (int i = 0; !bad && i < d->strata_count; i++) {
        if (d->strata[i] == ROCKS_BLOCK_DEFAULT) d->strata[i] = ROCKS_BLOCK_EQUIDIMENSIONAL;
        if ((unsigned)d->strata[i] >= ROCKS_BLOCK_TYPE_END) bad = "strata (a block type each)";
    }
    if (!bad && !(d->stratum_height >= 2.0f && d->stratum_height <= 1000.0f)) bad = "stratum_height (2 … 1000 m)";
    if (!bad && !(d->max_spacing > 0.0f && d->max_spacing <= 64.0f)) bad = "max_spacing (0 … 64 m)";
    if (!bad && !(d->block_scale >= 0.5f && d->block_scale <= 4.0f && d->tile_size * d->block_scale <= 64.0f))
        bad = "block_scale (0.5 … 4, tile_size · block_scale at most 64 m)";
    /* Only rock materials break into blocks: bedrock and a game's own materials (which the
     * terrain holds stable and solid like bedrock). Sand slides, rocks are piles, air and water
     * are no walls. */
    for (int m = 0; !bad && m < TERRAIN_MATERIAL_MAX; m++) {
        rocks_block_type type = d->material_blocks[m];
        if (type == ROCKS_BLOCK_DEFAULT) continue;
        if ((unsigned)type >= ROCKS_BLOCK_TYPE_END)
            snprintf(why, sizeof why, "material_blocks[%d] = %d (not a block type)", m, (int)type), bad = why;
        else if (m != TERRAIN_BEDROCK && m < TERRAIN_MATERIAL_BUILTIN_COUNT)
            snprintf(why, sizeof why, "material_blocks[%d] (%s is not a rock material)", m,
                     terrain_material_name((terrain_material)m)), bad = why;
    }
    if (bad) core_log_error("rocks", "cliffs: bad %s", bad);
    return bad == NULL;
}

/* The tiles to make: one per type the strata use, each built (or read) on its own. */
typedef struct tile_jobs {
    const rocks_cliffs_desc *desc;
    rocks_block_type types[ROCKS_BLOCK_TYPE_COUNT];
    rocks_block_tile *tiles[ROCKS_BLOCK_TYPE_COUNT];
} tile_jobs;

static void make_tiles(void *user, size_t begin, size_t end) {
    tile_jobs *jobs = user;
    const rocks_cliffs_desc *d = jobs->desc;
    for (size_t i = begin; i < end; i++) {
        rocks_block_type type = jobs->types[i];
        char *path = NULL;
        size_t path_size = 0;
        if (d->cache_dir) {   /* one file per type and seed: worlds of other seeds keep theirs */
            path_size = strlen(d->cache_dir) + 64;
            path = core_alloc(path_size);
            /* a scaled set keeps its own file beside the default one */
            char scale[16] = "";
            if (d->block_scale != 1.0f) snprintf(scale, sizeof scale, "-x%.2f", (double)d->block_scale);
            snprintf(path, path_size, "%s/blocks-%s-%016llx%s.bin", d->cache_dir, rocks_block_type_name(type),
                     (unsigned long long)d->seed, scale);
        }
        /* Scaled blocks: the side, the fractures' spacing and radius together (the points'
         * spacing follows the side), so the shapes stay and only their size changes. */
        float spacing, radius;
        rocks__block_type_defaults(type, &spacing, &radius);
        /* no relief: its 8 cm are below the metre the world samples at (the renderer's detail
         * layer shades the faces) and it would double the cost of every sample */
        jobs->tiles[i] = rocks_block_tile_create(&(rocks_block_tile_desc){
            .type = type, .seed = core_hash_combine(d->seed, (uint64_t)(type - ROCKS_BLOCK_EQUIDIMENSIONAL)),
            .size = d->tile_size * d->block_scale, .joint = d->joint,
            .fracture_spacing = spacing * d->block_scale, .fracture_radius = radius * d->block_scale,
            .relief = -1.0f, .cache_path = path });
        if (path) core_free(path, path_size);
    }
}

/* What a copy's presence reads lies within its block's bounds (its anchor and extreme points)
 * and PRESENCE_READS past them, and the values it adds lie within those bounds. So a cell's
 * presence reads the blocks' overhang past the cell and PRESENCE_READS more (tiles of 16 m
 * overhang by about 7 m: more than the 2 m once assumed), and a changed column changes values
 * at most a block's extent and PRESENCE_READS away, along each axis (a column 17 m tall and
 * 4 m wide reaches far up and down, not sideways). And its widest block: a coarse field that
 * shows none of the tile's blocks skips the type. */
static void cliffs_measure_tile(rocks_cliffs *c, int type) {
    const rocks_block_tile *tile = c->tiles[type];
    double overhang = 0.0;
    for (int a = 0; a < 3; a++) {
        overhang = fmax(overhang, -(double)tile->reach_min[a]);
        overhang = fmax(overhang, (double)tile->reach_max[a] - tile->desc.size);
    }
    for (uint32_t b = 0; b < tile->block_count; b++)
        for (int a = 0; a < 3; a++) {
            double extent = (double)tile->blocks[b].bounds_max[a] - tile->blocks[b].bounds_min[a];
            c->reach[a] = fmaxf(c->reach[a], (float)(extent + PRESENCE_READS));
        }
    for (uint32_t b = 0; b < tile->block_count; b++) c->widest[type] = fmaxf(c->widest[type], tile->widths[b]);
    c->margin[type] = overhang + PRESENCE_READS;
    c->margin_max = fmax(c->margin_max, c->margin[type]);
}

void rocks_cliffs_reach(const rocks_cliffs *cliffs, float reach[3]) {
    for (int a = 0; a < 3; a++) reach[a] = cliffs ? cliffs->reach[a] : 0.0f;
}

rocks_cliffs *rocks_cliffs_create(const rocks_cliffs_desc *desc) {
    rocks_cliffs_desc d;
    if (!cliffs_desc_make(desc, &d)) return NULL;
    rocks_cliffs *c = core_calloc(1, sizeof *c);
    static uint64_t next_id;
    c->id = __atomic_add_fetch(&next_id, 1, __ATOMIC_RELAXED);
    c->desc = d;
    c->desc.cache_dir = NULL, c->desc.jobs = NULL;   /* used here only: not kept */
    pthread_mutex_init(&c->lock, NULL);
    c->cache = core_calloc(CACHE_CAPACITY, sizeof *c->cache);
    uint64_t start = core_time_ns();
    tile_jobs jobs = { .desc = &d };
    size_t count = 0;
    bool used[ROCKS_BLOCK_TYPE_END] = { false };
    for (int m = 0; m < TERRAIN_MATERIAL_MAX; m++)
        if (d.material_blocks[m] != ROCKS_BLOCK_DEFAULT) c->type_materials[d.material_blocks[m]] |= 1u << m, c->mapped |= 1u << m;
    c->bedrock_in_strata = d.material_blocks[TERRAIN_BEDROCK] == ROCKS_BLOCK_DEFAULT;
    /* a tile per type some rock can break into: the strata's while bedrock follows them */
    for (int i = 0; c->bedrock_in_strata && i < d.strata_count; i++)
        if (!used[d.strata[i]]) used[d.strata[i]] = true, jobs.types[count++] = d.strata[i];
    for (int type = ROCKS_BLOCK_EQUIDIMENSIONAL; type < ROCKS_BLOCK_TYPE_END; type++)
        if (c->type_materials[type] && !used[type]) used[type] = true, jobs.types[count++] = (rocks_block_type)type;
    if (d.jobs) job_parallel_for(d.jobs, count, 1, make_tiles, &jobs, "rocks_block_tile");
    else make_tiles(&jobs, 0, count);
    bool ok = true;
    for (size_t i = 0; i < count; i++) {
        c->tiles[jobs.types[i]] = jobs.tiles[i];
        if (!jobs.tiles[i]) ok = false;
        else c->words[jobs.types[i]] = (jobs.tiles[i]->block_count + 63) / 64;
        if (jobs.tiles[i]) c->stats.blocks += jobs.tiles[i]->block_count;
        if (jobs.tiles[i] && jobs.tiles[i]->from_cache) c->stats.tiles_from_cache++;
    }
    if (!ok) {
        rocks_cliffs_destroy(c);
        return NULL;
    }
    for (int type = 0; type < ROCKS_BLOCK_TYPE_END; type++)
        if (c->tiles[type]) cliffs_measure_tile(c, type);
    c->stats.build_seconds = (double)(core_time_ns() - start) * 1e-9;
    c->stats.tile_size = d.tile_size * d.block_scale;
    return c;
}

static void cache_clear(rocks_cliffs *c) {
    for (size_t i = 0; i < CACHE_CAPACITY; i++)
        if (c->cache[i].key) core_free(c->cache[i].bits, c->words[c->cache[i].type] * sizeof(uint64_t));
    memset(c->cache, 0, CACHE_CAPACITY * sizeof *c->cache);
    c->used = 0;
}

void rocks_cliffs_destroy(rocks_cliffs *c) {
    if (!c) return;
    cache_clear(c);
    core_free(c->cache, CACHE_CAPACITY * sizeof *c->cache);
    for (int t = 0; t < ROCKS_BLOCK_TYPE_END; t++) rocks_block_tile_destroy(c->tiles[t]);
    pthread_mutex_destroy(&c->lock);
    core_free(c, sizeof *c);
}

rocks_cliffs_stats_info rocks_cliffs_stats(const rocks_cliffs *c) {
    pthread_mutex_t *lock = (pthread_mutex_t *)&c->lock;   /* a lock is not the cliffs' state */
    pthread_mutex_lock(lock);
    rocks_cliffs_stats_info s = c->stats;
    pthread_mutex_unlock(lock);
    s.fields = __atomic_load_n(&c->fields, __ATOMIC_RELAXED);
    s.copies_present = __atomic_load_n(&c->copies_present, __ATOMIC_RELAXED);
    s.amplify_seconds = (double)__atomic_load_n(&c->amplify_ns, __ATOMIC_RELAXED) * 1e-9;
    return s;
}

/* ---- presence (003 §5) -------------------------------------------------------------------------- */

static int stratum_type(const rocks_cliffs_desc *d, double y) {
    int64_t band = (int64_t)floor(y / d->stratum_height), n = d->strata_count;
    return (int)d->strata[((band % n) + n) % n];
}

/* Whether some height in [y0, y1) belongs to a stratum of `type`: a tile cell whose anchors all
 * lie in other strata has no block of this type present, and is not asked. */
static bool stratum_meets(const rocks_cliffs_desc *d, int type, double y0, double y1) {
    for (int64_t band = (int64_t)floor(y0 / d->stratum_height); (double)band * d->stratum_height < y1; band++) {
        int64_t n = d->strata_count;
        if ((int)d->strata[((band % n) + n) % n] == type) return true;
    }
    return false;
}

/* Whether a tile cell over heights [y0, y1) may hold a present block of `type`: bedrock in a
 * stratum of it there, or a material mapped to it anywhere (its layers may lie at any height;
 * cell_presence then asks the cell's columns, anchor by anchor). With no material mapped this is
 * the strata's test alone, as before materials could decide. */
static bool cell_may_hold(const rocks_cliffs *c, int type, double y0, double y1) {
    if (c->type_materials[type]) return true;
    return c->bedrock_in_strata && stratum_meets(&c->desc, type, y0, y1);
}

/* The block type a wall of `material` breaks into at height y (003 §5: γ(a_k) against the
 * block's material): its entry, else bedrock's stratum, else none (0). */
static int rock_type(const rocks_cliffs *c, terrain_material material, double y) {
    if ((unsigned)material >= TERRAIN_MATERIAL_MAX) return ROCKS_BLOCK_DEFAULT;
    if (c->desc.material_blocks[material] != ROCKS_BLOCK_DEFAULT) return (int)c->desc.material_blocks[material];
    if (material == TERRAIN_BEDROCK) return stratum_type(&c->desc, y);
    return ROCKS_BLOCK_DEFAULT;
}

/* The block type of the wall at anchor a (rock_type), or 0 where there is none: on a steep wall
 * (rocks_block_on_walls) at least 2 m tall, whose inside, three quarters of a metre along the
 * field's gradient, is a rock material (no blocks on steep sand). 003 §5 reads the material at
 * the anchor; ours may lie in front of the face, so the material behind it is read.
 *
 * The anchor may lie up to the field's clamp (1 m) inside the face: a block of a few metres whose
 * centroid is a metre deep still stands out of the face, and on the generator's curved walls
 * the narrower band left most of a wall bare. */
#define BEHIND_THE_FACE 0.75          /* metres from the anchor to where its material is read */

static int wall_type(const rocks_cliffs *c, terrain_world *world, const double a[3]) {
    rocks_wall_presence walls = { .world = world, .steepness = c->desc.steepness, .depth_min = c->desc.depth_min,
                                  .depth_max = c->desc.depth_max };
    if (walls.depth_min == 0 && walls.depth_max == 0) walls.depth_min = -0.6f, walls.depth_max = 1.0f;
    float g[3];
    if (!rocks__wall_at(&walls, a, g)) return ROCKS_BLOCK_DEFAULT;
    /* a wall, not a step: a metre above and below, the face is still near and still steep (a
     * shard on a knee-high step reads as debris, not as a cliff). Near, not at the anchor's
     * depth: a wall that leans by 30° moves half a metre over that metre. */
    rocks_wall_presence near = walls;
    near.depth_min = -0.99f, near.depth_max = 0.99f;
    for (int side = -1; side <= 1; side += 2) {
        const double b[3] = { a[0], a[1] + 1.0 * side, a[2] };
        if (!rocks_block_on_walls(&near, 0, b)) return ROCKS_BLOCK_DEFAULT;
    }
    double length = sqrt((double)g[0] * g[0] + (double)g[1] * g[1] + (double)g[2] * g[2]);
    terrain_material inside = terrain_world_material_at(world, a[0] + BEHIND_THE_FACE * g[0] / length,
                                                        a[1] + BEHIND_THE_FACE * g[1] / length,
                                                        a[2] + BEHIND_THE_FACE * g[2] / length);
    return rock_type(c, inside, a[1]);
}

/* 003 §5 with a set of anchors ("more than half ... satisfy"): the block's extreme points along
 * each axis must be mostly inside the wall or within half a metre of its face, so a long block
 * whose centre sits at the face does not stand metres out of it; and its highest point must be
 * one of them: a column whose foot is in the wall's top would stand over the rim as a spike. */
static bool mostly_in_the_wall(terrain_world *world, const rocks_block *b, const float (*points)[3], double ox, double oy,
                               double oz) {
    if (b->point_count == 0) return true;
    int inside = 0;
    bool top_inside = false;
    for (int a = 0; a < 3; a++)
        for (int side = 0; side < 2; side++) {
            const float *best = points[b->point_first];
            for (uint32_t i = 1; i < b->point_count; i++) {
                const float *p = points[b->point_first + i];
                if (side ? p[a] > best[a] : p[a] < best[a]) best = p;
            }
            bool in = terrain_field_base_at(world, ox + best[0], oy + best[1], oz + best[2], 0) >= -0.5f;
            inside += in;
            if (a == 1 && side == 1) top_inside = in;
        }
    return inside >= 4 && top_inside;
}

/* ---- a cheap first test: anchors far from any surface ------------------------------------- */

/* The field at p is 2·(solid fraction of the cube p ± 1 m) − 1 (terrain_field_base_at), and the
 * wall test reads it up to a quarter metre further (its gradient). So an anchor whose cube
 * p ± ANCHOR_REACH lies wholly above every column chunk's highest interface (terrain_stacks_
 * interface_range) sees only air, f = −1 exactly, and fails the distance range; wholly below
 * the lowest, only solid, f = 1 and a gradient of exactly zero: it fails the steepness. Such
 * anchors, most of a cell's, are passed over without the field's cost, with the same answer. */
#define ANCHOR_REACH 1.25

/* The chunks' bounds are coarse: a chunk that holds a canyon wall spans its whole height, and
 * on seed 1's canyon three anchors in four that pass them lie in solid rock. So each column the
 * anchors' cubes reach also keeps, read once a cell when first asked, its runs of solid (in-field)
 * material: a cube within one run of every column it meets, or between runs in all of them, sees
 * one material. */
#define SPAN_RUNS_MAX 3               /* solid runs kept of a column (more: no shortcut there) */
#define COLUMN_LAYERS_MAX 64          /* layers read of a column (more: no shortcut there) */

typedef struct column_span {
    int count;                        /* solid runs; 0 not read yet, −1 too many to keep */
    double bottom[SPAN_RUNS_MAX], top[SPAN_RUNS_MAX];  /* the first one's bottom −∞: the floor's solid */
} column_span;

typedef struct surface_bounds {
    int64_t chunk_x0, chunk_z0;       /* the cell's first column chunk */
    int nx, nz;                       /* chunks it spans (1 or 2 each way at s ≤ 32 m) */
    float lowest[3][3], highest[3][3];
    const terrain_stacks *stacks[3][3];   /* [k][i]: for materials_near */
    int64_t column_x0, column_z0;     /* the first column the cell's anchors' cubes reach */
    int columns;                      /* per axis */
    column_span *spans;               /* columns², allocated when first asked (surface_bounds_free) */
} surface_bounds;

/* The column chunk (terrain_chunk_coord) holding world coordinate x (or z). */
static int64_t chunk_of(double x) {
    return (int64_t)floor(x / (TERRAIN_CHUNK_COLUMNS * TERRAIN_COLUMN_SIZE));
}

static bool surface_bounds_make(terrain_world *world, const int64_t cell[3], double s, surface_bounds *b) {
    b->chunk_x0 = chunk_of((double)cell[0] * s - ANCHOR_REACH);
    b->chunk_z0 = chunk_of((double)cell[2] * s - ANCHOR_REACH);
    b->nx = (int)(chunk_of((double)cell[0] * s + s + ANCHOR_REACH) - b->chunk_x0 + 1);
    b->nz = (int)(chunk_of((double)cell[2] * s + s + ANCHOR_REACH) - b->chunk_z0 + 1);
    if (b->nx > 3 || b->nz > 3) return false;   /* a tile wider than a chunk: no shortcut */
    for (int k = 0; k < b->nz; k++)
        for (int i = 0; i < b->nx; i++) {
            const terrain_stacks *stacks =
                terrain_world_stacks(world, (terrain_chunk_coord){ b->chunk_x0 + i, b->chunk_z0 + k });
            if (!stacks) return false;
            b->stacks[k][i] = stacks;
            terrain_stacks_interface_range(stacks, &b->lowest[k][i], &b->highest[k][i]);
        }
    b->column_x0 = (int64_t)floor((double)cell[0] * s - ANCHOR_REACH);
    b->column_z0 = (int64_t)floor((double)cell[2] * s - ANCHOR_REACH);
    const int64_t columns = (int64_t)floor((double)cell[0] * s + s + ANCHOR_REACH) - b->column_x0 + 1;
    b->columns = (int)columns;
    b->spans = NULL;
    return true;
}

static void surface_bounds_free(surface_bounds *b) {
    if (b->spans) core_free(b->spans, (size_t)b->columns * (size_t)b->columns * sizeof *b->spans);
    b->spans = NULL;
}

/* Column (gx, gz)'s solid runs, read from its stacks the first time a cell asks. */
static const column_span *column_span_of(surface_bounds *b, int64_t gx, int64_t gz) {
    if (!b->spans) b->spans = core_calloc((size_t)b->columns * (size_t)b->columns, sizeof *b->spans);
    column_span *span = &b->spans[(gz - b->column_z0) * b->columns + (gx - b->column_x0)];
    if (span->count) return span;
    const int64_t cx = chunk_of((double)gx * TERRAIN_COLUMN_SIZE), cz = chunk_of((double)gz * TERRAIN_COLUMN_SIZE);
    terrain_layer layers[COLUMN_LAYERS_MAX];
    int count = terrain_stacks_column(b->stacks[cz - b->chunk_z0][cx - b->chunk_x0], (int)(gx - cx * TERRAIN_CHUNK_COLUMNS),
                                      (int)(gz - cz * TERRAIN_CHUNK_COLUMNS), layers, COLUMN_LAYERS_MAX);
    span->count = 1;   /* below the floor: solid */
    span->bottom[0] = -INFINITY, span->top[0] = TERRAIN_FLOOR_Y;
    double bottom = TERRAIN_FLOOR_Y;
    for (int l = 0; l < count && span->count >= 0; l++) {
        double top = bottom + (double)layers[l].thickness;
        if (terrain_material_in_field(layers[l].material) && layers[l].thickness > 0) {
            if (span->top[span->count - 1] == bottom) span->top[span->count - 1] = top;   /* go on */
            else if (span->count == SPAN_RUNS_MAX) span->count = -1;
            else span->bottom[span->count] = bottom, span->top[span->count++] = top;
        }
        bottom = top;
    }
    if (count > COLUMN_LAYERS_MAX) span->count = -1;
    return span;
}

/* The same test against the columns the anchor's cube meets: within one solid run of each, or
 * clear of every run in all of them. Exact as the chunks' test is: the cube sees one material. */
static bool far_from_columns(surface_bounds *b, const double a[3]) {
    const int64_t x0 = (int64_t)floor(a[0] - ANCHOR_REACH), x1 = (int64_t)floor(a[0] + ANCHOR_REACH);
    const int64_t z0 = (int64_t)floor(a[2] - ANCHOR_REACH), z1 = (int64_t)floor(a[2] + ANCHOR_REACH);
    if (x0 < b->column_x0 || z0 < b->column_z0 || x1 >= b->column_x0 + b->columns || z1 >= b->column_z0 + b->columns)
        return false;   /* an anchor outside its cell (none in the generated tiles) */
    const double lo = a[1] - ANCHOR_REACH, hi = a[1] + ANCHOR_REACH;
    bool empty = true, solid = true;
    for (int64_t gz = z0; gz <= z1 && (empty || solid); gz++)
        for (int64_t gx = x0; gx <= x1 && (empty || solid); gx++) {
            const column_span *span = column_span_of(b, gx, gz);
            if (span->count < 0) return false;
            bool within = false, clear = true;
            for (int r = 0; r < span->count; r++) {
                within |= span->bottom[r] < lo && hi < span->top[r];
                clear &= span->top[r] < lo || hi < span->bottom[r];
            }
            solid &= within, empty &= clear;
        }
    return empty || solid;
}

static bool far_from_surface(surface_bounds *b, const double a[3]) {
    int i0 = (int)(chunk_of(a[0] - ANCHOR_REACH) - b->chunk_x0), i1 = (int)(chunk_of(a[0] + ANCHOR_REACH) - b->chunk_x0);
    int k0 = (int)(chunk_of(a[2] - ANCHOR_REACH) - b->chunk_z0), k1 = (int)(chunk_of(a[2] + ANCHOR_REACH) - b->chunk_z0);
    bool above = true, below = true;
    for (int k = k0; k <= k1; k++)
        for (int i = i0; i <= i1; i++) {
            above &= a[1] - ANCHOR_REACH > (double)b->highest[k][i];
            below &= a[1] + ANCHOR_REACH < (double)b->lowest[k][i];
        }
    return above || below || far_from_columns(b, a);
}

/* ---- a second, when materials are mapped: no rock of the type near ---------------------------- */

/* wall_type reads the material BEHIND_THE_FACE from the anchor, so inside the box a ±
 * BEHIND_THE_FACE: the layers that meet that box (a little wider, against rounding) hold it. A
 * cell with no material of the type near (nor bedrock in a stratum of it) has no block of the
 * type; where rocks of other types lie near too, an anchor with none of the type near is passed
 * over; both without the field's cost. (Without mapped materials the strata's height test is
 * exact and cheaper.) The boxes lie within ANCHOR_REACH of the cell, so within the bounds'
 * chunks. On seed 1's cliffs (a 128 × 96 × 128 m box of level-0 fields, release, 2 cores) a
 * table that maps only a material the world lacks finds the same 696 copies as the strata in
 * the same time (0.32 s of presence either way), and bedrock mapped to tabular the same 838 as
 * one tabular stratum (0.40 s either way; 0.45 s with per-anchor reads alone). */
#define MATERIAL_REACH (BEHIND_THE_FACE + 1.0 / 16.0)

static int64_t column_of(double x) { return (int64_t)floor(x / TERRAIN_COLUMN_SIZE); }

/* The materials (a bit each) of the layers that meet the box [lo, hi], in the columns it
 * covers (within the bounds' chunks); all of them when a column holds more layers than read. */
static uint32_t materials_in(const surface_bounds *b, const double lo[3], const double hi[3]) {
    uint32_t mask = lo[1] < TERRAIN_FLOOR_Y ? 1u << TERRAIN_BEDROCK : 0;   /* below the floor */
    for (int64_t gz = column_of(lo[2]); gz <= column_of(hi[2]); gz++)
        for (int64_t gx = column_of(lo[0]); gx <= column_of(hi[0]); gx++) {
            const int64_t cx = chunk_of((double)gx * TERRAIN_COLUMN_SIZE), cz = chunk_of((double)gz * TERRAIN_COLUMN_SIZE);
            const terrain_stacks *stacks = b->stacks[cz - b->chunk_z0][cx - b->chunk_x0];
            terrain_layer layers[COLUMN_LAYERS_MAX];
            int count = terrain_stacks_column(stacks, (int)(gx - cx * TERRAIN_CHUNK_COLUMNS),
                                              (int)(gz - cz * TERRAIN_CHUNK_COLUMNS), layers, COLUMN_LAYERS_MAX);
            if (count > COLUMN_LAYERS_MAX) return UINT32_MAX;
            double bottom = TERRAIN_FLOOR_Y;
            for (int l = 0; l < count && bottom < hi[1]; l++) {
                double top = bottom + (double)layers[l].thickness;
                if (top > lo[1]) mask |= 1u << layers[l].material;
                bottom = top;
            }
        }
    return mask;
}

/* Those within MATERIAL_REACH of anchor a. */
static uint32_t materials_near(const surface_bounds *b, const double a[3]) {
    const double lo[3] = { a[0] - MATERIAL_REACH, a[1] - MATERIAL_REACH, a[2] - MATERIAL_REACH };
    const double hi[3] = { a[0] + MATERIAL_REACH, a[1] + MATERIAL_REACH, a[2] + MATERIAL_REACH };
    return materials_in(b, lo, hi);
}

/* Those within MATERIAL_REACH of the tile cell at `cell` (side s): of every anchor it holds. */
static uint32_t cell_materials(const surface_bounds *b, const int64_t cell[3], double s) {
    double lo[3], hi[3];
    for (int a = 0; a < 3; a++) lo[a] = (double)cell[a] * s - MATERIAL_REACH, hi[a] = (double)cell[a] * s + s + MATERIAL_REACH;
    return materials_in(b, lo, hi);
}

/* What a cell's anchors must pass before the wall test, worked out once a cell from the
 * materials near it. Without materials mapped, only the strata: an anchor in another type's
 * stratum is bedrock of that type (exact, as before materials could decide). */
typedef struct anchor_filter {
    bool none;                        /* no anchor of the cell can hold the type */
    bool by_stratum;                  /* only bedrock in a stratum of the type gives it */
    bool by_columns;                  /* rocks of other types lie near: each anchor reads its columns */
    bool bedrock_in_strata;           /* bedrock with no entry lies near */
} anchor_filter;

static anchor_filter anchor_filter_make(const rocks_cliffs *c, const surface_bounds *b, bool have_bounds, int type,
                                        const int64_t cell[3], double s) {
    anchor_filter f = { .by_stratum = c->type_materials[type] == 0 };
    if (!c->mapped || !have_bounds) return f;
    const uint32_t near = cell_materials(b, cell, s), mine = near & c->type_materials[type];
    f.bedrock_in_strata = c->bedrock_in_strata && (near & 1u << TERRAIN_BEDROCK);
    if (!mine) {   /* a game's rock that lies in a few places skips every other cell at once */
        f.none = !(f.bedrock_in_strata && stratum_meets(&c->desc, type, (double)cell[1] * s, (double)cell[1] * s + s));
        f.by_stratum = true;
        return f;
    }
    /* where every rock near is of the type (a wall of one mapped rock), the wall test alone decides */
    f.by_columns = (near & c->mapped & ~c->type_materials[type]) || f.bedrock_in_strata;
    return f;
}

/* An anchor of a cell with a material of the type near: bedrock in its stratum, or a material of
 * the type within the wall test's reach. */
static bool anchor_near_type(const rocks_cliffs *c, const anchor_filter *f, const surface_bounds *b, int type,
                             const double a[3]) {
    if (!f->by_columns || (f->bedrock_in_strata && stratum_type(&c->desc, a[1]) == type)) return true;
    return (materials_near(b, a) & c->type_materials[type]) != 0;
}

/* The column chunks' versions one amplify call reads, each looked up once (a lookup takes the
 * world's lock, and a call asks about its chunks for every cell and type). Versions change only
 * with commits, so a call first reads the world's commit count: a cell kept at that count is
 * still right, and the table is made only when some cell was kept at another. */
#define VERSION_TABLE_MAX 64

typedef struct version_table {
    terrain_world *world;
    uint32_t commits;                 /* the world's commit count when the call began */
    double lo[3], hi[3], margin;      /* the chunks to hold, once made */
    bool made;
    int64_t x0, z0;
    int nx, nz;                       /* 0 when the call's chunks are too many to hold */
    uint32_t version[VERSION_TABLE_MAX];
} version_table;

static void version_table_begin(version_table *t, terrain_world *world, const double lo[3], const double hi[3],
                                double margin) {
    t->world = world;
    t->commits = terrain_world_commit_count(world);
    memcpy(t->lo, lo, sizeof t->lo);
    memcpy(t->hi, hi, sizeof t->hi);
    t->margin = margin;
    t->made = false;
}

static void version_table_make(version_table *t) {
    t->made = true;
    t->x0 = chunk_of(t->lo[0] - t->margin), t->z0 = chunk_of(t->lo[2] - t->margin);
    int64_t nx = chunk_of(t->hi[0] + t->margin) - t->x0 + 1, nz = chunk_of(t->hi[2] + t->margin) - t->z0 + 1;
    t->nx = t->nz = 0;
    if (nx * nz > VERSION_TABLE_MAX) return;
    t->nx = (int)nx, t->nz = (int)nz;
    for (int k = 0; k < t->nz; k++)
        for (int i = 0; i < t->nx; i++)
            t->version[k * t->nx + i] = terrain_world_chunk_version(t->world, (terrain_chunk_coord){ t->x0 + i, t->z0 + k });
}

static uint32_t version_of(version_table *t, int64_t x, int64_t z) {
    if (!t->made) version_table_make(t);
    int64_t i = x - t->x0, k = z - t->z0;
    if (i >= 0 && k >= 0 && i < t->nx && k < t->nz) return t->version[k * t->nx + i];
    return terrain_world_chunk_version(t->world, (terrain_chunk_coord){ x, z });
}

/* The versions of the column chunks under the cell (and the margin its presence reads). */
static uint64_t cell_versions(version_table *t, const int64_t cell[3], double s, double margin) {
    int64_t x0 = chunk_of((double)cell[0] * s - margin), x1 = chunk_of((double)cell[0] * s + s + margin);
    int64_t z0 = chunk_of((double)cell[2] * s - margin), z1 = chunk_of((double)cell[2] * s + s + margin);
    uint64_t h = 0x51ed27;
    for (int64_t z = z0; z <= z1; z++)
        for (int64_t x = x0; x <= x1; x++) h = core_hash_combine(h, version_of(t, x, z));
    return h;
}

static uint64_t cell_key(int type, const int64_t cell[3]) {
    uint64_t h = core_hash_combine((uint64_t)type + 1, (uint64_t)cell[0]);
    h = core_hash_combine(h, (uint64_t)cell[1]);
    h = core_hash_combine(h, (uint64_t)cell[2]);
    return h ? h : 1;
}

/* Sets the bits of the present blocks of `type`'s copy at `cell` among those wider than `above`
 * and not wider than `known`. The shortcuts (bounds, materials near) pass over anchors whose
 * answer they know without the field's cost; without them every anchor is asked (the tests'
 * check that they change nothing). */
static void presence_work_out(rocks_cliffs *c, terrain_world *world, int type, const int64_t cell[3], float above,
                              float known, bool shortcuts, uint64_t *bits) {
    const rocks_block_tile *tile = c->tiles[type];
    const double s = tile->desc.size;
    surface_bounds bounds = { 0 };
    /* made at the first anchor that may hold `type`, or at once when materials are mapped */
    int shortcut = !shortcuts ? 0 : c->mapped ? surface_bounds_make(world, cell, s, &bounds) : -1;
    const anchor_filter filter = anchor_filter_make(c, &bounds, shortcut > 0, type, cell, s);
    for (uint32_t b = 0; !filter.none && b < tile->block_count; b++) {
        double anchor[3];
        for (int a = 0; a < 3; a++) anchor[a] = (double)cell[a] * s + tile->blocks[b].anchor[a];
        if (filter.by_stratum && stratum_type(&c->desc, anchor[1]) != type) continue;
        if (!(tile->widths[b] > above && tile->widths[b] <= known)) continue;   /* not asked, or known */
        if (shortcut < 0) shortcut = surface_bounds_make(world, cell, s, &bounds);
        if (shortcut && far_from_surface(&bounds, anchor)) continue;
        if (shortcut > 0 && !anchor_near_type(c, &filter, &bounds, type, anchor)) continue;
        if (wall_type(c, world, anchor) == type &&
            mostly_in_the_wall(world, &tile->blocks[b], tile->points, (double)cell[0] * s, (double)cell[1] * s,
                               (double)cell[2] * s))
            bits[b / 64] |= 1ull << (b % 64);
    }
    surface_bounds_free(&bounds);
}

/* The cache's slot for (type, cell): its entry, or the empty slot where it would go (lock held). */
static cell_entry *cache_slot(rocks_cliffs *c, uint64_t key, int type, const int64_t cell[3]) {
    for (size_t i = key & (CACHE_CAPACITY - 1);; i = (i + 1) & (CACHE_CAPACITY - 1)) {
        cell_entry *e = &c->cache[i];
        if (!e->key || (e->key == key && e->type == type && !memcmp(e->cell, cell, sizeof e->cell))) return e;
    }
}

/* The cache's entry for (type, cell), or NULL (lock held). */
static cell_entry *cache_find(rocks_cliffs *c, uint64_t key, int type, const int64_t cell[3]) {
    cell_entry *e = cache_slot(c, key, type, cell);
    return e->key ? e : NULL;
}

/* Each thread's last answers, kept beside the shared cache: the samples of a picking ray or a
 * collision query ask the same few cells over and over, and the shared cache's lock, taken a
 * cell at a time, cost more than the answer (about half of a sample through the hook). An entry
 * is right for its owner while the world's commit count is the one it was kept at. */
#define MEMO_SLOTS 32                 /* a power of two */
#define MEMO_WORDS 8                  /* tiles of up to 512 blocks; bigger ones are not kept */

typedef struct memo_entry {
    uint64_t owner;                   /* rocks_cliffs.id; 0 = empty */
    uint32_t commits;
    int type;
    int64_t cell[3];
    float known_above;
    uint64_t bits[MEMO_WORDS];
} memo_entry;

static _Thread_local memo_entry memo[MEMO_SLOTS];

static memo_entry *memo_slot(uint64_t key) { return &memo[key & (MEMO_SLOTS - 1)]; }

static bool memo_get(const rocks_cliffs *c, uint64_t key, uint32_t commits, int type, const int64_t cell[3],
                     float above, uint64_t *bits) {
    const memo_entry *m = memo_slot(key);
    if (m->owner != c->id || m->commits != commits || m->type != type || memcmp(m->cell, cell, sizeof m->cell) ||
        !(m->known_above <= above))
        return false;
    memcpy(bits, m->bits, c->words[type] * sizeof *bits);
    return true;
}

static void memo_put(const rocks_cliffs *c, uint64_t key, uint32_t commits, int type, const int64_t cell[3],
                     float known_above, const uint64_t *bits) {
    if (c->words[type] > MEMO_WORDS) return;
    memo_entry *m = memo_slot(key);
    *m = (memo_entry){ .owner = c->id, .commits = commits, .type = type, .known_above = known_above };
    memcpy(m->cell, cell, sizeof m->cell);
    memcpy(m->bits, bits, c->words[type] * sizeof *bits);
}

/* The present blocks of `type`'s tile copy at `cell` among those wider than `above` metres, into
 * bits (c->words[type] words; the others' bits 0): from the cache when its versions still hold
 * and it knows those blocks, else worked out and kept. A coarse field shows only blocks wider
 * than 1.5 spacings (rocks__coarse_min_width), so the far rings ask about a few of a cell's blocks,
 * and a finer field later adds the rest to the same entry. Presence is per block, so a block's
 * bit is the same whichever field asked first. */
static void cell_presence(rocks_cliffs *c, version_table *table, int type, const int64_t cell[3], float above,
                          uint64_t *bits) {
    const rocks_block_tile *tile = c->tiles[type];
    const size_t words = c->words[type];
    const uint64_t key = cell_key(type, cell);
    uint64_t versions = 0;            /* read when the count does not tell (cache_find) */
    float known = INFINITY;           /* the blocks wider than this are in bits already */
    if (memo_get(c, key, table->commits, type, cell, above, bits)) return;
    memset(bits, 0, words * sizeof *bits);
    pthread_mutex_lock(&c->lock);
    cell_entry *e = cache_find(c, key, type, cell);
    if (e && e->commits != table->commits) {   /* kept before some commit: are its chunks' the same? */
        const uint32_t kept = e->commits;
        pthread_mutex_unlock(&c->lock);   /* the versions take the world's lock */
        versions = cell_versions(table, cell, tile->desc.size, c->margin[type]);
        pthread_mutex_lock(&c->lock);
        e = cache_find(c, key, type, cell);
        if (e && e->commits == kept) {
            if (e->versions != versions) e = NULL;
            else e->commits = table->commits;
        }
        /* (else another thread brought it up to date meanwhile, or it went: asked again below) */
        if (e && e->commits != table->commits) e = NULL;
    }
    if (e) {
        memcpy(bits, e->bits, words * sizeof *bits);
        known = e->known_above;
        if (known <= above) {
            c->stats.cells_reused++;
            pthread_mutex_unlock(&c->lock);
            memo_put(c, key, table->commits, type, cell, known, bits);
            return;
        }
        versions = e->versions;   /* it knows the wider blocks only: add the others */
    }
    pthread_mutex_unlock(&c->lock);
    if (!e) versions = cell_versions(table, cell, tile->desc.size, c->margin[type]);

    const uint64_t presence_start = core_time_ns();
    presence_work_out(c, table->world, type, cell, above, known, true, bits);

    pthread_mutex_lock(&c->lock);
    c->stats.cells_computed++;
    c->stats.presence_seconds += (double)(core_time_ns() - presence_start) * 1e-9;
    if (c->used >= CACHE_CAPACITY * 3 / 4) cache_clear(c);
    e = cache_slot(c, key, type, cell);
    if (!e->key) {
        *e = (cell_entry){ .key = key, .type = type, .bits = core_alloc(words * sizeof *bits) };
        memcpy(e->cell, cell, sizeof e->cell);
        c->used++;
    }
    e->versions = versions;   /* an older entry for the cell is brought up to date */
    e->commits = table->commits;
    e->known_above = above;
    memcpy(e->bits, bits, words * sizeof *bits);
    pthread_mutex_unlock(&c->lock);
    memo_put(c, key, table->commits, type, cell, above, bits);
}

/* ---- the tests' view -------------------------------------------------------------------------- */

const rocks_block_tile *rocks__cliffs_tile(const rocks_cliffs *c, rocks_block_type type) {
    return (unsigned)type < ROCKS_BLOCK_TYPE_END ? c->tiles[type] : NULL;
}

/* Every block of the cell, as level 0: through the hook's path (its cache and shortcuts), or
 * anchor by anchor with neither. */
static bool cliffs_present(rocks_cliffs *c, terrain_world *world, rocks_block_type type, const int64_t cell[3],
                           bool hook_path, uint64_t *bits) {
    const rocks_block_tile *tile = rocks__cliffs_tile(c, type);
    if (!tile) return false;
    const double s = tile->desc.size;
    memset(bits, 0, c->words[type] * sizeof *bits);
    if (!cell_may_hold(c, (int)type, (double)cell[1] * s, (double)cell[1] * s + s)) return false;
    if (!hook_path) {
        presence_work_out(c, world, (int)type, cell, -INFINITY, INFINITY, false, bits);
        return true;
    }
    double lo[3], hi[3];
    for (int a = 0; a < 3; a++) lo[a] = (double)cell[a] * s, hi[a] = lo[a] + s;
    version_table versions;
    version_table_begin(&versions, world, lo, hi, c->margin_max);
    cell_presence(c, &versions, (int)type, cell, -INFINITY, bits);
    return true;
}

bool rocks__cliffs_present(rocks_cliffs *c, terrain_world *world, rocks_block_type type, const int64_t cell[3],
                           uint64_t *bits) {
    return cliffs_present(c, world, type, cell, true, bits);
}

bool rocks__cliffs_present_unfiltered(rocks_cliffs *c, terrain_world *world, rocks_block_type type,
                                      const int64_t cell[3], uint64_t *bits) {
    return cliffs_present(c, world, type, cell, false, bits);
}

/* ---- the hook ---------------------------------------------------------------------------------- */

/* Each present block copy of the cells that the box [lo, hi] may meet, among the blocks wider
 * than `above`, handed to visit. */
typedef void copy_visit(void *user, const rocks_block_tile *tile, int type, uint32_t block, const double cell[3]);

static void present_copies(rocks_cliffs *c, terrain_world *world, const double lo[3], const double hi[3],
                           float above, copy_visit *visit, void *user) {
    int64_t c0[ROCKS_BLOCK_TYPE_END][3], c1[ROCKS_BLOCK_TYPE_END][3];
    double reach_lo[3] = { INFINITY, INFINITY, INFINITY }, reach_hi[3] = { -INFINITY, -INFINITY, -INFINITY };
    for (int type = 0; type < ROCKS_BLOCK_TYPE_END; type++) {
        const rocks_block_tile *tile = c->tiles[type];
        if (!tile || !(c->widest[type] > above)) continue;
        rocks__cell_range(tile, lo, hi, c0[type], c1[type]);
        for (int a = 0; a < 3; a++) {
            reach_lo[a] = fmin(reach_lo[a], (double)c0[type][a] * tile->desc.size);
            reach_hi[a] = fmax(reach_hi[a], (double)(c1[type][a] + 1) * tile->desc.size);
        }
    }
    if (!(reach_lo[0] <= reach_hi[0])) return;   /* no tiles */
    version_table versions;
    version_table_begin(&versions, world, reach_lo, reach_hi, c->margin_max);
    uint64_t bits[64];
    for (int type = 0; type < ROCKS_BLOCK_TYPE_END; type++) {
        const rocks_block_tile *tile = c->tiles[type];
        if (!tile || !(c->widest[type] > above) || c->words[type] > CORE_COUNTOF(bits)) continue;
        const double s = tile->desc.size;
        for (int64_t z = c0[type][2]; z <= c1[type][2]; z++)
            for (int64_t y = c0[type][1]; y <= c1[type][1]; y++)
                for (int64_t x = c0[type][0]; x <= c1[type][0]; x++) {
                    const int64_t cell[3] = { x, y, z };
                    if (!cell_may_hold(c, type, (double)y * s, (double)y * s + s)) continue;
                    /* every cell the blocks' union reaches is asked once and kept (asking which
                     * block reaches the box cost more than the cached answer, for the small
                     * fields of collision) */
                    cell_presence(c, &versions, type, cell, above, bits);
                    const double at[3] = { (double)x, (double)y, (double)z };
                    for (size_t w = 0; w < c->words[type]; w++)
                        for (uint64_t m = bits[w]; m; m &= m - 1)
                            visit(user, tile, type, (uint32_t)(w * 64 + (size_t)__builtin_ctzll(m)), at);
                }
    }
}

typedef struct field_copies {
    terrain_field *field;
    uint64_t present;
} field_copies;

static void amplify_visit(void *user, const rocks_block_tile *tile, int type, uint32_t block, const double cell[3]) {
    (void)type;
    field_copies *f = user;
    f->present += rocks__amplify_copy(tile, block, cell, f->field);
}

/* Points and small fields. A picking ray, a camera test or a walk's probe asks the field one
 * point at a time, a few hundred a frame, and the player's collision asks a small box each frame,
 * mostly the same box as the frame before. Through the cells' presence, each went through ranges,
 * lookups, then every present block of each cell only to find most of them far away: a point cost
 * three times its terrain field. A thread keeps, for the last few boxes it asked, the present
 * copies whose bounds meet the box; asking again is then the fields of those few blocks. A point's
 * box is the 2 m region it lies in, so a ray's samples share one; a small field's box is its own.
 * There are slots enough for a whole picking ray's regions, so the next frame's ray, a few
 * centimetres on, finds them again. An entry holds while the world's commit count is the one it
 * was made at, as the cells' memo does. */
#define REGION_SIZE 2.0
#define SMALL_FIELD 512               /* samples at most in a field whose box is kept */
#define REGION_SLOTS 64               /* a power of two */
#define REGION_COPIES 48              /* a box meeting more is not kept: asked the long way */

_Static_assert(ROCKS_BLOCK_TYPE_END <= 8, "a block type fits in a region copy's 3 bits");

/* What a thread's kept answer for a box is about: the cliffs, the world's commit count, the
 * field's spacing (it sets the blocks shown) and the box. */
typedef struct kept_box {
    uint64_t owner;                   /* rocks_cliffs.id; 0 = an empty slot */
    uint32_t commits;
    float spacing;
    double lo[3], hi[3];
} kept_box;

static kept_box kept_box_make(const rocks_cliffs *c, uint32_t commits, float spacing, const double lo[3],
                              const double hi[3]) {
    kept_box k = { .owner = c->id, .commits = commits, .spacing = spacing };
    memcpy(k.lo, lo, sizeof k.lo), memcpy(k.hi, hi, sizeof k.hi);
    return k;
}

static bool kept_box_same(const kept_box *a, const kept_box *b) {
    return a->owner == b->owner && a->commits == b->commits && a->spacing == b->spacing &&
           !memcmp(a->lo, b->lo, sizeof a->lo) && !memcmp(a->hi, b->hi, sizeof a->hi);
}

/* The slot of `slots` (a power of two) a box's answer is kept in. */
static size_t kept_box_slot(const kept_box *k, size_t slots) {
    uint64_t key = 0x9e3779b9;
    for (int a = 0; a < 3; a++) {
        uint64_t l, h;
        memcpy(&l, &k->lo[a], sizeof l), memcpy(&h, &k->hi[a], sizeof h);
        key = core_hash_combine(core_hash_combine(key, l), h);
    }
    return (size_t)(key & (slots - 1));
}

typedef struct region_copy {          /* 16 bytes: the slots stay small */
    int32_t cell[3];
    uint32_t block_type;              /* block << 3 | type */
} region_copy;

typedef struct region_memo {
    kept_box box;
    int count;                        /* copies; -1 when too many */
    region_copy copies[REGION_COPIES];
} region_memo;

static _Thread_local region_memo regions[REGION_SLOTS];

/* Whether the copy of block `block` at `cell` may meet the box [lo, hi] (its bounds do). */
static bool copy_meets(const rocks_block_tile *tile, uint32_t block, const double cell[3], const double lo[3],
                       const double hi[3]) {
    const rocks_block *b = &tile->blocks[block];
    const double s = tile->desc.size;
    for (int a = 0; a < 3; a++)
        if (cell[a] * s + b->bounds_max[a] < lo[a] || cell[a] * s + b->bounds_min[a] > hi[a]) return false;
    return true;
}

static void region_visit(void *user, const rocks_block_tile *tile, int type, uint32_t block, const double cell[3]) {
    region_memo *r = user;
    if (r->count < 0 || !copy_meets(tile, block, cell, r->box.lo, r->box.hi)) return;
    bool fits = r->count < REGION_COPIES && block < (UINT32_MAX >> 3);
    for (int a = 0; a < 3; a++) fits &= fabs(cell[a]) < (double)INT32_MAX;   /* else not kept */
    if (!fits) {
        r->count = -1;
        return;
    }
    r->copies[r->count++] = (region_copy){ .cell = { (int32_t)cell[0], (int32_t)cell[1], (int32_t)cell[2] },
                                           .block_type = block << 3 | (uint32_t)type };
}

/* Most of a picking ray's samples lie in open air or deep in rock, far from any block, and a 2 m
 * region made for each four of them cost more than the samples' terrain field. A thread also
 * keeps, for the 8 m regions its points fell in lately, whether any copy meets them: a point in
 * an empty one needs nothing more. */
#define EMPTY_SIZE 8.0
#define EMPTY_SLOTS 32                /* a power of two */

typedef struct empty_memo {
    kept_box box;
    bool empty;                       /* no copy meets the region */
} empty_memo;

static _Thread_local empty_memo empties[EMPTY_SLOTS];

static void empty_visit(void *user, const rocks_block_tile *tile, int type, uint32_t block, const double cell[3]) {
    (void)type;
    empty_memo *e = user;
    if (e->empty && copy_meets(tile, block, cell, e->box.lo, e->box.hi)) e->empty = false;
}

/* Whether no copy meets the 8 m region of a one-sample field's point. A region asked anew starts
 * the clock (*start). */
static bool point_far_from_blocks(rocks_cliffs *c, terrain_world *world, const terrain_field *field, float above,
                                  uint64_t *start) {
    double lo[3], hi[3];
    for (int a = 0; a < 3; a++) lo[a] = floor(field->origin[a] / EMPTY_SIZE) * EMPTY_SIZE, hi[a] = lo[a] + EMPTY_SIZE;
    const kept_box box = kept_box_make(c, terrain_world_commit_count(world), field->spacing, lo, hi);
    empty_memo *e = &empties[kept_box_slot(&box, EMPTY_SLOTS)];
    if (!kept_box_same(&e->box, &box)) {
        *start = core_time_ns();
        *e = (empty_memo){ .box = box, .empty = true };
        present_copies(c, world, lo, hi, above, empty_visit, e);
    }
    return e->empty;
}

/* The field within [lo, hi] (a box holding its samples) from the copies its thread kept for that
 * box; false when the box meets too many to keep. A box made anew starts the clock (*start). */
static bool amplify_kept(rocks_cliffs *c, terrain_world *world, terrain_field *field, const double lo[3],
                         const double hi[3], float above, uint64_t *present, uint64_t *start) {
    const kept_box box = kept_box_make(c, terrain_world_commit_count(world), field->spacing, lo, hi);
    region_memo *r = &regions[kept_box_slot(&box, REGION_SLOTS)];
    if (!kept_box_same(&r->box, &box)) {
        *start = core_time_ns();
        *r = (region_memo){ .box = box };
        present_copies(c, world, lo, hi, above, region_visit, r);
    }
    if (r->count < 0) return false;
    for (int i = 0; i < r->count; i++) {
        const region_copy *k = &r->copies[i];
        const double cell[3] = { k->cell[0], k->cell[1], k->cell[2] };
        *present += rocks__amplify_copy(c->tiles[k->block_type & 7], k->block_type >> 3, cell, field);
    }
    return true;
}

void rocks_cliffs_amplify(void *user, terrain_world *world, terrain_field *field) {
    rocks_cliffs *c = user;
    if (field->spacing > c->desc.max_spacing) return;   /* the same for every field at a spacing */
    /* a coarse field shows only the blocks wider than this (rocks__coarse_erosion) */
    const float above = rocks__coarse_min_width(field->spacing);
    field_copies copies = { .field = field };
    /* the box the samples lie in, and the box a thread keeps its copies for */
    const int n[3] = { field->nx, field->ny, field->nz };
    double lo[3], hi[3], kept_lo[3], kept_hi[3];
    for (int a = 0; a < 3; a++) lo[a] = field->origin[a], hi[a] = field->origin[a] + (n[a] - 1) * (double)field->spacing;
    const bool point = n[0] == 1 && n[1] == 1 && n[2] == 1;
    for (int a = 0; a < 3; a++) {
        kept_lo[a] = point ? floor(lo[a] / REGION_SIZE) * REGION_SIZE : lo[a];
        kept_hi[a] = point ? kept_lo[a] + REGION_SIZE : hi[a];
    }
    uint64_t start = 0;   /* a box its thread kept goes untimed: the clock cost a quarter of a point */
    if (point && point_far_from_blocks(c, world, field, above, &start)) {
        /* nothing to raise */
    } else if ((size_t)n[0] * n[1] * n[2] > SMALL_FIELD ||
               !amplify_kept(c, world, field, kept_lo, kept_hi, above, &copies.present, &start)) {
        if (!start) start = core_time_ns();
        present_copies(c, world, lo, hi, above, amplify_visit, &copies);
    }
    __atomic_add_fetch(&c->fields, 1, __ATOMIC_RELAXED);
    __atomic_add_fetch(&c->copies_present, copies.present, __ATOMIC_RELAXED);
    if (start) __atomic_add_fetch(&c->amplify_ns, core_time_ns() - start, __ATOMIC_RELAXED);
}
