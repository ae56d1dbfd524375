/* rocks_system.c — rocks in the running world: the RockTiles component on level-0 mesh chunks,
 * the system that places them with jobs, and the collision queries against the placed rocks.
 *
 * A chunk's rocks are a pure function of the stacks their anchors can reach: the chunk's column
 * chunk and its 8 neighbours (a rock reaches at most its radius, under a metre, past the chunk
 * whose box holds its seed). So a placement remembers the versions of those 9 column chunks
 * (terrain_world_chunk_version) and is made again, in the same frame, when any of them changes:
 * an edit that empties a rock layer removes exactly the rocks whose anchors left it, and a rock
 * layer dropped by the sand tool fills with rocks in the frame it is committed.
 */
#include "rocks_world_internal.h"

#include <math.h>
#include <string.h>

#include "core/core.h"
#include "ecs/ecs.h"
#include "gfx/gfx.h"
#include "jobs/jobs.h"
#include "trace/trace.h"

#define ROCKS_REACH_AHEAD 16.0f       /* metres past range where chunks are placed ahead */
#define ROCKS_REACH_KEEP 32.0f        /* metres past range where placements are kept */
#define ROCKS_NEW_PER_FRAME 6         /* placements of chunks not yet in range a frame */
#define ROCKS_MAX_WORK 64

struct rocks_system {
    rocks_system_desc desc;
    rocks_place_index *index;         /* the tile set laid out for placement, made once */
    rocks_place_desc place;
    ecs_component mesh_chunk, tiles;
    ecs_query *placed;                /* TerrainMeshChunk with RockTiles */
    ecs_system system;
    terrain_view view;
    bool has_view;
    rocks_renderer *renderer;
    rocks_system_stats_info stats;
    /* rocks_focus: the rocks near a box, so that many queries in it skip the chunks' lists */
    double focus_lo[3], focus_hi[3];
    bool focus_valid;
    struct focus_rock { double origin[3]; uint32_t rock; } *focus;
    size_t focus_count, focus_capacity;
};

bool rocks_parse_quality(const char *text, rocks_quality *out) {
    if (!text) return false;
    if (strcmp(text, "off") == 0) *out = ROCKS_OFF;
    else if (strcmp(text, "on") == 0) *out = ROCKS_ON;
    else return false;
    return true;
}

/* ---- the component's life ------------------------------------------------------------------- */

static void rock_tiles_removed(ecs_world *world, ecs_entity entity, void *data, void *user) {
    (void)world, (void)entity;
    RockTiles *tiles = data;
    rocks_system *r = user;
    if (r) {
        r->stats.chunks--;
        r->stats.instances -= tiles->placement.count;
    }
    rocks_placement_free(&tiles->placement);
}

/* ---- placing -------------------------------------------------------------------------------- */

typedef struct place_work {
    ecs_entity entity;
    RockTiles *existing;              /* NULL: a new component */
    RockTiles result;
    double min[3], max[3];
} place_work;

typedef struct place_batch {
    rocks_system *r;
    place_work *work;
} place_batch;

static void place_range(void *user, size_t first, size_t last) {
    place_batch *b = user;
    for (size_t i = first; i < last; i++) {
        TRACE_ZONE("rocks.place_chunk");
        place_work *w = &b->work[i];
        rocks_place_box(&b->r->place, w->min, w->max, &w->result.placement);
    }
}

/* The versions of the 9 column chunks a level-0 mesh chunk's rocks read. */
static uint64_t chunk_source(rocks_system *r, const TerrainMeshChunk *c) {
    uint64_t h = core_hash_combine((uint64_t)c->x * 0x9e37u, (uint64_t)c->y ^ ((uint64_t)c->z << 20));
    for (int dz = -1; dz <= 1; dz++)
        for (int dx = -1; dx <= 1; dx++)
            h = core_hash_combine(h, terrain_world_chunk_version(r->desc.world,
                                                                 (terrain_chunk_coord){ c->x + dx, c->z + dz }));
    return h;
}

static double box_distance(const double camera[3], const double lo[3], const double hi[3]) {
    double squares = 0;
    for (int a = 0; a < 3; a++) {
        double d = camera[a] < lo[a] ? lo[a] - camera[a] : camera[a] > hi[a] ? camera[a] - hi[a] : 0.0;
        squares += d * d;
    }
    return sqrt(squares);
}

static void chunk_box(const TerrainMeshChunk *c, double lo[3], double hi[3]) {
    const double size = TERRAIN_MESH_CELLS * TERRAIN_COLUMN_SIZE;
    lo[0] = (double)c->x * size, lo[1] = (double)c->y * size, lo[2] = (double)c->z * size;
    for (int a = 0; a < 3; a++) hi[a] = lo[a] + size;
}

static void rocks_place_system(ecs_iter *it) {
    rocks_system *r = it->user;
    uint64_t start = core_time_ns();
    place_work work[ROCKS_MAX_WORK];
    int count = 0, fresh = 0;
    while (ecs_query_next(it)) {
        TerrainMeshChunk *chunks = ecs_field(it, 0);
        RockTiles *tiles = ecs_field(it, 1);
        for (int i = 0; i < it->count; i++) {
            const TerrainMeshChunk *c = &chunks[i];
            RockTiles *have = tiles && ecs_field_is_set(it, 1) ? &tiles[i] : NULL;
            double lo[3], hi[3];
            chunk_box(c, lo, hi);
            double distance = r->has_view ? box_distance(r->view.camera, lo, hi) : INFINITY;
            /* A chunk waiting to be meshed again (an edit) keeps its rocks meanwhile; a new one is
             * placed once its terrain is meshed, so rocks never show before their ground. */
            bool wanted = r->desc.quality != ROCKS_OFF && r->has_view && c->lod.level == 0 && !c->hidden &&
                          (have || c->state != TERRAIN_MESH_WAITING) &&
                          distance <= r->desc.range + (have ? ROCKS_REACH_KEEP : ROCKS_REACH_AHEAD);
            if (have && !wanted) {
                ecs_defer_remove(it->commands, it->entities[i], r->tiles);
                continue;
            }
            if (!wanted || count == ROCKS_MAX_WORK) continue;
            uint64_t source = chunk_source(r, c);
            if (have && have->source == source) continue;
            if (!have && distance > r->desc.range && fresh >= ROCKS_NEW_PER_FRAME) continue;
            place_work *w = &work[count++];
            *w = (place_work){ .entity = it->entities[i], .existing = have };
            if (have) w->result.placement = have->placement;     /* reuse its memory */
            w->result.source = source;
            memcpy(w->min, lo, sizeof lo);
            memcpy(w->max, hi, sizeof hi);
            if (!have) fresh++;
        }
    }
    if (count) {
        place_batch batch = { r, work };
        job_system *jobs = ecs_world_jobs(r->desc.ecs);
        if (jobs) job_parallel_for(jobs, (size_t)count, 1, place_range, &batch, "rocks.place");
        else place_range(&batch, 0, (size_t)count);
    }
    if (count) r->focus_valid = false;
    for (int i = 0; i < count; i++) {
        place_work *w = &work[i];
        if (w->existing) {
            r->stats.instances -= w->existing->placement.count;
            *w->existing = w->result;
            r->stats.instances += w->result.placement.count;
        } else {
            ecs_defer_set(it->commands, w->entity, r->tiles, &w->result);
            r->stats.chunks++;
            r->stats.instances += w->result.placement.count;
        }
        r->stats.placements++;
    }
    r->stats.place_ms = (double)(core_time_ns() - start) * 1e-6;
    trace_counter("rocks.chunks", (double)r->stats.chunks);
    trace_counter("rocks.instances", (double)r->stats.instances);
}

/* ---- the system ----------------------------------------------------------------------------- */

static void rocks_defaults(rocks_system_desc *d) {
    if (d->quality == ROCKS_DEFAULT) d->quality = ROCKS_ON;
    if (!(d->tile_size > 0)) d->tile_size = 3.0f;
    if (!(d->range > 0)) d->range = 70.0f;
    if (!(d->lod_distance[0] > 0)) d->lod_distance[0] = 10.0f;
    if (!(d->lod_distance[1] > 0)) d->lod_distance[1] = 25.0f;
    if (d->fog_density == 0) d->fog_density = 0.0025f;
}

rocks_system *rocks_system_create(const rocks_system_desc *desc) {
    if (!desc || !desc->gfx || !desc->ecs || !desc->world || !desc->tiles) {
        core_log_error("rocks", "rocks_system_create needs .gfx, .ecs, .world and .tiles");
        return NULL;
    }
    ecs_component mesh_chunk = ecs_component_lookup(desc->ecs, "TerrainMeshChunk");
    if (!mesh_chunk) {
        core_log_error("rocks", "no TerrainMeshChunk in this ECS world: call terrain_ecs_create first");
        return NULL;
    }
    rocks_renderer *renderer = rocks__renderer_create(desc->gfx, desc->tiles);
    if (!renderer) return NULL;
    rocks_system *r = core_calloc(1, sizeof *r);
    r->desc = *desc;
    rocks_defaults(&r->desc);
    r->renderer = renderer;
    r->index = rocks_place_index_create(desc->tiles);
    r->place = (rocks_place_desc){ .tiles = desc->tiles, .index = r->index, .world = desc->world,
                                   .tile_size = r->desc.tile_size };
    r->mesh_chunk = mesh_chunk;
    r->tiles = ecs_component_lookup(desc->ecs, "RockTiles");
    if (!r->tiles) r->tiles = ECS_COMPONENT(desc->ecs, RockTiles);
    ecs_component_on_remove(desc->ecs, r->tiles, rock_tiles_removed, r);
    r->placed = ecs_query_create(desc->ecs, &(ecs_query_desc){ .with = { mesh_chunk, r->tiles } });
    r->system = ecs_system_add(desc->ecs, &(ecs_system_desc){ .name = "rocks_place", .phase = "draw",
        .query = { .with = { mesh_chunk }, .optional = { r->tiles } }, .writes = { r->tiles },
        .fn = rocks_place_system, .user = r, .main_thread = true });
    return r;
}

void rocks_system_destroy(rocks_system *r) {
    if (!r) return;
    ecs_system_enable(r->desc.ecs, r->system, false);
    /* Free every placement now (the components stay, empty: a later rocks_system_create places again). */
    ecs_component_on_remove(r->desc.ecs, r->tiles, NULL, NULL);
    ecs_iter it = ecs_query_iter(r->desc.ecs, r->placed);
    while (ecs_query_next(&it)) {
        RockTiles *tiles = ecs_field(&it, 1);
        for (int i = 0; i < it.count; i++) {
            rocks_placement_free(&tiles[i].placement);
            tiles[i].source = 0;
        }
    }
    ecs_component_on_remove(r->desc.ecs, r->tiles, rock_tiles_removed, NULL);
    rocks__renderer_destroy(r->renderer);
    rocks_place_index_destroy(r->index);
    core_free(r->focus, r->focus_capacity * sizeof *r->focus);
    core_free(r, sizeof *r);
}

void rocks_set_view(rocks_system *r, const terrain_view *view) {
    r->view = *view;
    r->has_view = true;
}

rocks_system_stats_info rocks_system_stats(const rocks_system *r) {
    rocks_system_stats_info s = r->stats;
    s.tiles_bytes = r->desc.tiles ? r->desc.tiles->bytes : 0;
    s.placed_bytes = (size_t)s.instances * sizeof(rocks_instance);
    s.gpu_bytes = rocks__renderer_gpu_bytes(r->renderer);
    s.draw_bytes = rocks__renderer_cpu_bytes(r->renderer);
    return s;
}

/* ---- drawing -------------------------------------------------------------------------------- */

void rocks_draw(rocks_system *r, const terrain_view *view) {
    if (r->desc.quality == ROCKS_OFF) return;
    uint64_t start = core_time_ns();
    terrain_frustum frustum = terrain_frustum_from_view(view);
    const rocks_placement *list[256];
    int n = 0;
    ecs_iter it = ecs_query_iter(r->desc.ecs, r->placed);
    while (ecs_query_next(&it)) {
        const RockTiles *tiles = ecs_field(&it, 1);
        for (int i = 0; i < it.count && n < 256; i++) {
            const rocks_placement *p = &tiles[i].placement;
            if (!p->count || !terrain_frustum_sees(&frustum, p->origin, p->bounds_min, p->bounds_max)) continue;
            double lo[3], hi[3];
            for (int a = 0; a < 3; a++) lo[a] = p->origin[a] + p->bounds_min[a], hi[a] = p->origin[a] + p->bounds_max[a];
            if (box_distance(view->camera, lo, hi) > r->desc.range) continue;
            list[n++] = p;
        }
    }
    rocks_draw_desc params = { .tile_size = r->desc.tile_size, .range = r->desc.range,
                                 .fog_density = r->desc.fog_density,
                                 .lod_distance = { r->desc.lod_distance[0], r->desc.lod_distance[1] } };
    r->stats.instances_drawn = rocks__renderer_draw(r->renderer, view, &params, list, n, &r->stats.triangles_drawn);
    r->stats.draw_ms = (double)(core_time_ns() - start) * 1e-6;
}

/* ---- collision ------------------------------------------------------------------------------ */

typedef bool (*rock_visit_fn)(void *user, const rocks_rock *rock, const double origin[3], uint32_t rock_index);

static bool rock_meets(const rocks_rock *rock, const double origin[3], double tile, const double lo[3],
                       const double hi[3]) {
    for (int a = 0; a < 3; a++)
        if (origin[a] + rock->bounds_min[a] * tile > hi[a] || origin[a] + rock->bounds_max[a] * tile < lo[a])
            return false;
    return true;
}

static bool focus_holds(const rocks_system *r, const double lo[3], const double hi[3]) {
    if (!r->focus_valid) return false;
    for (int a = 0; a < 3; a++)
        if (lo[a] < r->focus_lo[a] || hi[a] > r->focus_hi[a]) return false;
    return true;
}

/* Calls fn for every placed rock whose box meets [lo, hi] (world metres) until fn returns false:
 * the focus list when it covers the box, else every placement that meets it. */
static void visit_near(rocks_system *r, const double lo[3], const double hi[3], rock_visit_fn fn, void *user) {
    if (r->desc.quality == ROCKS_OFF) return;
    const rocks_tileset *set = r->desc.tiles;
    const double tile = r->desc.tile_size;
    if (focus_holds(r, lo, hi)) {
        for (size_t i = 0; i < r->focus_count; i++) {
            const rocks_rock *rock = &set->rocks[r->focus[i].rock];
            if (rock_meets(rock, r->focus[i].origin, tile, lo, hi) && !fn(user, rock, r->focus[i].origin, r->focus[i].rock))
                return;
        }
        return;
    }
    ecs_iter it = ecs_query_iter(r->desc.ecs, r->placed);
    while (ecs_query_next(&it)) {
        const RockTiles *tiles = ecs_field(&it, 1);
        for (int c = 0; c < it.count; c++) {
            const rocks_placement *p = &tiles[c].placement;
            if (!p->count) continue;
            bool meets = true;
            for (int a = 0; a < 3; a++)
                meets = meets && p->origin[a] + p->bounds_min[a] <= hi[a] && p->origin[a] + p->bounds_max[a] >= lo[a];
            if (!meets) continue;
            for (uint32_t i = 0; i < p->count; i++) {
                const rocks_instance *in = &p->instances[i];
                const rocks_rock *rock = &set->rocks[in->rock];
                double origin[3] = { p->origin[0] + in->position[0], p->origin[1] + in->position[1],
                                     p->origin[2] + in->position[2] };
                if (rock_meets(rock, origin, tile, lo, hi) && !fn(user, rock, origin, in->rock)) return;
            }
        }
    }
}

static bool focus_visit(void *user, const rocks_rock *rock, const double origin[3], uint32_t index) {
    (void)rock;
    rocks_system *r = user;
    r->focus = core_grow(r->focus, &r->focus_capacity, r->focus_count + 1, sizeof *r->focus);
    r->focus[r->focus_count++] = (struct focus_rock){ { origin[0], origin[1], origin[2] }, index };
    return true;
}

void rocks_focus(rocks_system *r, const double min[3], const double max[3]) {
    r->focus_valid = false;
    r->focus_count = 0;
    visit_near(r, min, max, focus_visit, r);
    memcpy(r->focus_lo, min, sizeof r->focus_lo);
    memcpy(r->focus_hi, max, sizeof r->focus_hi);
    r->focus_valid = true;
}

typedef struct distance_query {
    double point[3];
    double tile;
    float best;
    float normal[3];
} distance_query;

static bool distance_visit(void *user, const rocks_rock *rock, const double origin[3], uint32_t index) {
    (void)index;
    distance_query *q = user;
    float local[3], normal[3];
    for (int a = 0; a < 3; a++) local[a] = (float)((q->point[a] - origin[a]) / q->tile);
    float d = rocks_hull_distance(rock, local, normal) * (float)q->tile;
    if (d < q->best) {
        q->best = d;
        memcpy(q->normal, normal, sizeof normal);
    }
    return true;
}

float rocks_distance(rocks_system *r, const double point[3], float max_distance, float normal[3]) {
    distance_query q = { .point = { point[0], point[1], point[2] }, .tile = r->desc.tile_size, .best = max_distance,
                         .normal = { 0.0f, 1.0f, 0.0f } };
    double lo[3], hi[3];
    for (int a = 0; a < 3; a++) lo[a] = point[a] - max_distance, hi[a] = point[a] + max_distance;
    visit_near(r, lo, hi, distance_visit, &q);
    if (normal) memcpy(normal, q.normal, sizeof q.normal);
    return q.best;
}

typedef struct ray_query {
    double origin[3];
    float direction[3];
    double tile;
    float best;
    rocks_ray_hit hit;
    bool found;
} ray_query;

/* The ray against the 26-DOP: the slab of each axis clips [t0, t1] (exact for the hull). */
static bool ray_visit(void *user, const rocks_rock *rock, const double origin[3], uint32_t index) {
    ray_query *q = user;
    float o[3];
    for (int a = 0; a < 3; a++) o[a] = (float)((q->origin[a] - origin[a]) / q->tile);
    float t0 = 0.0f, t1 = q->best / (float)q->tile;
    int enter_axis = -1;
    float enter_sign = 0.0f;
    for (int a = 0; a < ROCKS_HULL_AXES; a++) {
        const float *n = rocks_hull_axes[a];
        float od = n[0] * o[0] + n[1] * o[1] + n[2] * o[2];
        float dd = n[0] * q->direction[0] + n[1] * q->direction[1] + n[2] * q->direction[2];
        float lo = rock->hull[2 * a], hi = rock->hull[2 * a + 1];
        if (fabsf(dd) < 1e-9f) {
            if (od < lo || od > hi) return true;
            continue;
        }
        float ta = (lo - od) / dd, tb = (hi - od) / dd;
        float sign = -1.0f;           /* entering through the min plane: normal −n */
        if (ta > tb) {
            float s = ta;
            ta = tb, tb = s;
            sign = 1.0f;
        }
        if (ta > t0) t0 = ta, enter_axis = a, enter_sign = sign;
        if (tb < t1) t1 = tb;
        if (t0 > t1) return true;
    }
    float distance = t0 * (float)q->tile;
    if (distance >= q->best) return true;
    q->best = distance;
    q->found = true;
    for (int a = 0; a < 3; a++) q->hit.position[a] = q->origin[a] + (double)q->direction[a] * distance;
    if (enter_axis >= 0) {
        const float *n = rocks_hull_axes[enter_axis];
        float len = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int a = 0; a < 3; a++) q->hit.normal[a] = enter_sign * n[a] / len;
    } else {
        for (int a = 0; a < 3; a++) q->hit.normal[a] = -q->direction[a];   /* started inside */
    }
    q->hit.distance = distance;
    q->hit.rock = index;
    return true;
}

bool rocks_raycast(rocks_system *r, const double origin[3], const float direction[3], float max_distance,
                   rocks_ray_hit *hit) {
    float len = sqrtf(direction[0] * direction[0] + direction[1] * direction[1] + direction[2] * direction[2]);
    if (!(len > 0) || !(max_distance > 0)) return false;
    ray_query q = { .origin = { origin[0], origin[1], origin[2] },
                    .direction = { direction[0] / len, direction[1] / len, direction[2] / len },
                    .tile = r->desc.tile_size, .best = max_distance };
    double lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        double end = origin[a] + (double)q.direction[a] * max_distance;
        lo[a] = fmin(origin[a], end), hi[a] = fmax(origin[a], end);
    }
    visit_near(r, lo, hi, ray_visit, &q);
    if (q.found && hit) *hit = q.hit;
    return q.found;
}

/* ---- reading back --------------------------------------------------------------------------- */

uint64_t rocks_digest(rocks_system *r) {
    /* Order-independent: the sum of per-rock hashes (chunks come in any order). */
    uint64_t sum = 0, count = 0;
    ecs_iter it = ecs_query_iter(r->desc.ecs, r->placed);
    while (ecs_query_next(&it)) {
        const RockTiles *tiles = ecs_field(&it, 1);
        for (int c = 0; c < it.count; c++) {
            const rocks_placement *p = &tiles[c].placement;
            for (uint32_t i = 0; i < p->count; i++) {
                const rocks_instance *in = &p->instances[i];
                int64_t mm[3];
                for (int a = 0; a < 3; a++) mm[a] = llround((p->origin[a] + in->position[a]) * 1000.0);
                uint64_t h = core_hash_bytes(mm, sizeof mm, in->rock);
                sum += core_hash_combine(h, in->key);
                count++;
            }
        }
    }
    return core_hash_combine(sum, count);
}
