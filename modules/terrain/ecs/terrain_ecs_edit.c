/* terrain_ecs_edit.c — editing the terrain of a running world (terrain.h, "editing in the ECS").
 *
 * The stabilize phase ("terrain_stabilize", main thread):
 *   1. applies the edits queued since the last frame (terrain_world_edit);
 *   2. stabilizes the chunks edits touched (000 §3.4): one region of one chunk each, kept
 *      across frames until nothing moves; material that reaches a border wakes the chunk
 *      beyond, which joins (TERRAIN_EDGE_WAKE), so a slide crosses any number of chunks;
 *      a frame spends at most the settings' budget, then commits the chunks that changed;
 *   3. collects the world's changed chunks (from here or from anyone else's commits) for the
 *      mesh phase: static mesh chunks that read them go back to waiting, and the streamer
 *      remeshes its own at once (terrain_stream.c), so a stroke is drawn the frame it lands.
 * Regions always equal the world at the end of the phase (every change is committed), so an
 * edit of a chunk under stabilization simply reloads that chunk's region.
 */
#include "terrain/ecs/terrain_ecs_internal.h"

#include "core/core.h"
#include "ecs/ecs.h"
#include "trace/trace.h"

#include <math.h>
#include <string.h>

#define EDIT_DEFAULT_BUDGET_NS 2000000u
#define EDIT_DEFAULT_MAX_REGIONS 256
#define EDIT_CHANGES_PER_TAKE 64

typedef struct edit_region {
    terrain_chunk_coord coord;
    terrain_columns *columns;
} edit_region;

struct terrain__editor {
    terrain_editing_desc settings;        /* defaults filled in */
    terrain_edit *queue;                   /* sweep arrays point into owned copies */
    size_t queue_count, queue_capacity;
    edit_region *regions;                  /* chunks being stabilized */
    size_t region_count, region_capacity;
    terrain_columns **scratch;
    size_t scratch_capacity;
    terrain_ecs_edit_stats_info stats;
};

static terrain_editing_desc edit_defaults(const terrain_editing_desc *in) {
    terrain_editing_desc s = in ? *in : (terrain_editing_desc){ 0 };
    if (s.stabilize.budget_ns == 0 && s.stabilize.max_iterations == 0) s.stabilize.budget_ns = EDIT_DEFAULT_BUDGET_NS;
    if (s.max_regions <= 0) s.max_regions = EDIT_DEFAULT_MAX_REGIONS;
    s.stabilize.edge = TERRAIN_EDGE_WAKE;
    return s;
}

static terrain__editor *editor_get(terrain_ecs *te) {
    if (!te->editor) {
        te->editor = core_calloc(1, sizeof *te->editor);
        te->editor->settings = edit_defaults(NULL);
    }
    return te->editor;
}

/* ---- the queue ------------------------------------------------------------------------------ */

static void edit_free_copy(terrain_edit *e) {
    if (e->tool != TERRAIN_EDIT_SWEEP) return;
    core_free((void *)e->sweep.points, (size_t)e->sweep.point_count * sizeof *e->sweep.points);
    core_free((void *)e->sweep.radii, e->sweep.radii ? (size_t)e->sweep.point_count * sizeof *e->sweep.radii : 0);
    core_free((void *)e->sweep.segments, (size_t)e->sweep.segment_count * sizeof *e->sweep.segments);
    core_free((void *)e->sweep.profile, e->sweep.profile ? (size_t)e->sweep.profile_count * sizeof *e->sweep.profile : 0);
}

/* The sweep's arrays are the caller's: the queue keeps copies. */
static bool edit_copy(terrain_edit *out, const terrain_edit *in) {
    *out = *in;
    if (in->tool != TERRAIN_EDIT_SWEEP) return true;
    const terrain_sweep_desc *s = &in->sweep;
    if (!s->points || s->point_count <= 0 || s->point_count > 4096 || s->segment_count < 0 ||
        s->segment_count > 65536 || (s->segment_count > 0 && !s->segments) ||
        (s->profile && (s->profile_count < 3 || s->profile_count > 64))) return false;
    void *points = core_calloc((size_t)s->point_count, sizeof *s->points);
    memcpy(points, s->points, (size_t)s->point_count * sizeof *s->points);
    out->sweep.points = points;
    if (s->radii) {
        float *radii = core_calloc((size_t)s->point_count, sizeof *radii);
        memcpy(radii, s->radii, (size_t)s->point_count * sizeof *radii);
        out->sweep.radii = radii;
    }
    if (s->segment_count > 0) {
        void *segments = core_calloc((size_t)s->segment_count, sizeof *s->segments);
        memcpy(segments, s->segments, (size_t)s->segment_count * sizeof *s->segments);
        out->sweep.segments = segments;
    } else {
        out->sweep.segments = NULL;
    }
    if (s->profile) {
        float *profile = core_calloc((size_t)s->profile_count, sizeof *profile);
        memcpy(profile, s->profile, (size_t)s->profile_count * sizeof *profile);
        out->sweep.profile = profile;
    }
    return true;
}

bool terrain_ecs_edit(terrain_ecs *te, const terrain_edit *edit) {
    terrain__editor *ed = editor_get(te);
    if (!edit || edit->tool < TERRAIN_EDIT_SCULPT_ADD || edit->tool > TERRAIN_EDIT_ERODE) {
        core_log_error("terrain", "terrain_ecs_edit: tool %d is not a brush (sculpt, sweep, deposit, erode)",
                   edit ? (int)edit->tool : -1);
        ed->stats.edits_refused++;
        return false;
    }
    terrain_edit copy;
    if (!edit_copy(&copy, edit)) {
        core_log_error("terrain", "terrain_ecs_edit: a sweep needs 1 … 4096 points and its segments");
        ed->stats.edits_refused++;
        return false;
    }
    ed->queue = core_grow(ed->queue, &ed->queue_capacity, ed->queue_count + 1, sizeof *ed->queue);
    ed->queue[ed->queue_count++] = copy;
    return true;
}

/* ---- regions under stabilization ------------------------------------------------------------- */

static edit_region *region_find(terrain__editor *ed, terrain_chunk_coord coord) {
    for (size_t i = 0; i < ed->region_count; i++)
        if (ed->regions[i].coord.x == coord.x && ed->regions[i].coord.z == coord.z) return &ed->regions[i];
    return NULL;
}

/* Loads the chunk as the world has it now; `touch` makes the next stabilization look at every
 * column (a chunk an edit changed), else only at what flows in (a woken neighbour). */
static bool region_load(terrain_ecs *te, terrain_chunk_coord coord, bool touch) {
    terrain__editor *ed = te->editor;
    edit_region *r = region_find(ed, coord);
    if (!r) {
        if ((int)ed->region_count >= ed->settings.max_regions) return false;
        terrain_columns *columns = terrain_columns_create(&(terrain_columns_desc){
            .x = coord.x * TERRAIN_CHUNK_COLUMNS, .z = coord.z * TERRAIN_CHUNK_COLUMNS,
            .width = TERRAIN_CHUNK_COLUMNS, .depth = TERRAIN_CHUNK_COLUMNS });
        if (!columns) return false;
        ed->regions = core_grow(ed->regions, &ed->region_capacity, ed->region_count + 1, sizeof *ed->regions);
        r = &ed->regions[ed->region_count++];
        *r = (edit_region){ .coord = coord, .columns = columns };
    }
    terrain_columns_load(r->columns, coord, terrain_world_stacks(te->terrain, coord));
    terrain_columns_changed_chunks(r->columns, NULL, 0, true);
    if (touch) terrain_columns_touch(r->columns, 0, 0, TERRAIN_CHUNK_COLUMNS, TERRAIN_CHUNK_COLUMNS);
    return true;
}

static void regions_clear(terrain__editor *ed) {
    for (size_t i = 0; i < ed->region_count; i++) terrain_columns_destroy(ed->regions[i].columns);
    ed->region_count = 0;
}

/* Commits the regions whose columns changed this frame. */
static void regions_commit(terrain_ecs *te) {
    terrain__editor *ed = te->editor;
    for (size_t i = 0; i < ed->region_count; i++) {
        edit_region *r = &ed->regions[i];
        int32_t sea;
        /* What slid under water displaced it (its surface does not rise); what slid away from
         * under the sea's line lets the sea in (terrain.h, "the sea after edits"). */
        terrain__columns_cap_water(r->columns, r->coord, terrain_world_stacks(te->terrain, r->coord));
        if (terrain__world_sea(te->terrain, &sea)) terrain__columns_flood(r->columns, sea);
        if (terrain_columns_changed_chunks(r->columns, NULL, 0, true) == 0) continue;
        terrain_stacks *stacks = terrain_columns_to_stacks(r->columns, r->coord);
        if (!stacks) continue;
        terrain_world_commit(te->terrain, r->coord, stacks, TERRAIN_EDIT_STABILIZE);
        ed->stats.chunks_committed++;
    }
}

/* Up to the frame's budget; woken neighbours join and the call goes on with what is left. */
static void regions_stabilize(terrain_ecs *te) {
    terrain__editor *ed = te->editor;
    job_system *jobs = ecs_world_jobs(te->ecs);
    terrain_stabilize_desc params = ed->settings.stabilize;
    uint64_t start = core_time_ns();
    for (;;) {
        ed->scratch = core_grow(ed->scratch, &ed->scratch_capacity, ed->region_count, sizeof *ed->scratch);
        for (size_t i = 0; i < ed->region_count; i++) ed->scratch[i] = ed->regions[i].columns;
        terrain_stabilize_result result;
        if (!terrain_stabilize_regions(ed->scratch, (int)ed->region_count, &params, jobs, &result)) {
            regions_clear(ed);                 /* the reason is logged; nothing was changed */
            return;
        }
        ed->stats.iterations += (uint64_t)result.iterations;
        if (result.converged) {
            regions_commit(te);
            regions_clear(ed);
            return;
        }
        bool grew = false;
        /* Woken chunks lie beyond the regions; a region already held is never reloaded here
         * (that would drop this frame's moves). */
        for (int w = 0; w < result.woken_count && w < TERRAIN_STABILIZE_MAX_WOKEN; w++)
            if (!region_find(ed, result.woken[w])) grew |= region_load(te, result.woken[w], false);
        uint64_t spent = core_time_ns() - start;
        bool out_of_time = params.budget_ns && spent >= ed->settings.stabilize.budget_ns;
        if (result.woken_count == 0 || out_of_time) break;
        if (!grew) {
            /* At the region cap: what reaches the border stays there (a wall), for now. */
            core_warn("terrain", "stabilization reached %d chunks: its border holds like a wall",
                      ed->settings.max_regions);
            params.edge = TERRAIN_EDGE_WALL;
        }
        if (params.budget_ns) params.budget_ns = ed->settings.stabilize.budget_ns - spent;
        if (params.max_iterations) {
            params.max_iterations -= result.iterations;
            if (params.max_iterations <= 0) break;
        }
    }
    regions_commit(te);
}

/* ---- the phase ------------------------------------------------------------------------------ */

static void edits_apply(terrain_ecs *te) {
    terrain__editor *ed = te->editor;
    for (size_t q = 0; q < ed->queue_count; q++) {
        terrain_edit *edit = &ed->queue[q];
        terrain_chunk_coord changed[64];
        int n = terrain_world_edit(te->terrain, edit, changed, 64);
        if (n < 0) ed->stats.edits_refused++;
        else ed->stats.edits_applied++;
        for (int c = 0; c < n && c < 64; c++) region_load(te, changed[c], true);
        edit_free_copy(edit);
    }
    ed->queue_count = 0;
}

/* Its samples reach one apron sample and the kernel (one column, one metre up and down) beyond
 * the chunk, and the material weights a column more; its occlusion's rays reach farther still.
 * What amplify adds at any of those samples may depend on columns `amplify_reach` further (a
 * cliff block whose presence an edit beside the chunk changed reaches into it). */
bool terrain__mesh_reads_change(int level, int64_t x, int64_t y, int64_t z, const terrain_world_change *change,
                                const float amplify_reach[3]) {
    int64_t step = (int64_t)1 << level, size = TERRAIN_MESH_CELLS * step, pad = step + 2;
    if (pad < TERRAIN__MESH_OCCLUSION_REACH) pad = TERRAIN__MESH_OCCLUSION_REACH;   /* the occlusion's rays */
    const int64_t pad_x = pad + (int64_t)ceilf(amplify_reach[0]), pad_z = pad + (int64_t)ceilf(amplify_reach[2]);
    const double pad_y = (double)pad + ceil((double)amplify_reach[1]);
    int64_t lo_x = x * size - pad_x, hi_x = (x + 1) * size + pad_x;
    int64_t lo_z = z * size - pad_z, hi_z = (z + 1) * size + pad_z;
    double lo_y = (double)(y * size) - pad_y, hi_y = (double)((y + 1) * size) + pad_y;
    int64_t x0 = change->coord.x * TERRAIN_CHUNK_COLUMNS + change->column_min[0];
    int64_t x1 = change->coord.x * TERRAIN_CHUNK_COLUMNS + change->column_max[0];
    int64_t z0 = change->coord.z * TERRAIN_CHUNK_COLUMNS + change->column_min[1];
    int64_t z1 = change->coord.z * TERRAIN_CHUNK_COLUMNS + change->column_max[1];
    return hi_x >= x0 && lo_x <= x1 && hi_z >= z0 && lo_z <= z1 && hi_y >= change->y_min && lo_y <= change->y_max;
}

/* Static (not streamed) mesh chunks that read a changed chunk go back to waiting: the mesh
 * phase meshes them again; their old GPU mesh is drawn until the new one is up. */
static void static_meshes_invalidate(terrain_ecs *te, ecs_commands *commands) {
    if (te->changed_count == 0) return;
    const float *reach = terrain__world_amplify_reach(te->terrain);
    ecs_iter it = ecs_query_iter(te->ecs, te->mesh_chunks);
    while (ecs_query_next(&it)) {
        TerrainMeshChunk *chunks = ecs_field(&it, 0);
        for (int i = 0; i < it.count; i++) {
            TerrainMeshChunk *m = &chunks[i];
            ecs_entity e = it.entities[i];
            if (ecs_has(te->ecs, e, te->streamed) || m->state == TERRAIN_MESH_WAITING) continue;
            bool reads = false;
            for (size_t c = 0; c < te->changed_count && !reads; c++)
                reads = terrain__mesh_reads_change(m->lod.level, m->x, m->y, m->z, &te->changed[c], reach);
            if (!reads) continue;
            terrain_mesh_free(&m->mesh);
            m->state = TERRAIN_MESH_WAITING;
            m->edited = true;
            ecs_defer_remove(commands, e, te->mesh_ready);
            if (ecs_has(te->ecs, e, te->mesh_uploaded)) ecs_defer_remove(commands, e, te->mesh_uploaded);
        }
    }
}

/* Column-chunk entities point at their stacks: after a commit, at the new ones (the old ones are
 * freed at a later trim). */
static void chunk_entities_refresh(terrain_ecs *te) {
    if (te->changed_count == 0) return;
    ecs_iter it = ecs_query_iter(te->ecs, te->chunks);
    while (ecs_query_next(&it)) {
        TerrainChunk *chunks = ecs_field(&it, 0);
        for (int i = 0; i < it.count; i++) {
            if (!chunks[i].stacks) continue;
            for (size_t c = 0; c < te->changed_count; c++)
                if (te->changed[c].coord.x == chunks[i].coord.x && te->changed[c].coord.z == chunks[i].coord.z)
                    chunks[i].stacks = terrain_world_stacks(te->terrain, chunks[i].coord);
        }
    }
}

static void changes_collect(terrain_ecs *te) {
    te->changed_count = 0;
    for (;;) {
        te->changed = core_grow(te->changed, &te->changed_capacity, te->changed_count + EDIT_CHANGES_PER_TAKE,
                                sizeof *te->changed);
        int n = terrain_world_take_changes(te->terrain, te->changed + te->changed_count, EDIT_CHANGES_PER_TAKE);
        te->changed_count += (size_t)n;
        if (n < EDIT_CHANGES_PER_TAKE) break;
    }
}

static void terrain_stabilize_system(ecs_iter *it) {
    terrain_ecs *te = it->user;
    terrain__editor *ed = te->editor;
    if (ed && (ed->queue_count || ed->region_count)) {
        TRACE_ZONE("terrain_stabilize");
        uint64_t start = core_time_ns();
        edits_apply(te);
        if (ed->region_count) regions_stabilize(te);
        ed->stats.last_frame_ms = (double)(core_time_ns() - start) * 1e-6;
        trace_counter("terrain.edit.stabilizing_chunks", (double)ed->region_count);
    }
    changes_collect(te);
    if (te->changed_count) trace_counter("terrain.edit.changed_chunks", (double)te->changed_count);
    chunk_entities_refresh(te);
    static_meshes_invalidate(te, it->commands);
}

void terrain__editor_register(terrain_ecs *te) {
    ecs_system_add(te->ecs, &(ecs_system_desc){ .name = "terrain_stabilize", .phase = "stabilize",
        .writes = { te->chunk, te->mesh_chunk, te->self_resource }, .fn = terrain_stabilize_system, .user = te,
        .main_thread = true });
}

void terrain__editor_destroy(terrain_ecs *te) {
    terrain__editor *ed = te->editor;
    core_free(te->changed, te->changed_capacity * sizeof *te->changed);
    if (!ed) return;
    for (size_t q = 0; q < ed->queue_count; q++) edit_free_copy(&ed->queue[q]);
    regions_clear(ed);
    core_free(ed->queue, ed->queue_capacity * sizeof *ed->queue);
    core_free(ed->regions, ed->region_capacity * sizeof *ed->regions);
    core_free(ed->scratch, ed->scratch_capacity * sizeof *ed->scratch);
    core_free(ed, sizeof *ed);
    te->editor = NULL;
}

/* ---- the API -------------------------------------------------------------------------------- */

void terrain_ecs_set_editing(terrain_ecs *te, const terrain_editing_desc *settings) {
    editor_get(te)->settings = edit_defaults(settings);
}

terrain_ecs_edit_stats_info terrain_ecs_edit_stats(const terrain_ecs *te) {
    const terrain__editor *ed = te->editor;
    if (!ed) return (terrain_ecs_edit_stats_info){ 0 };   /* nothing edited yet */
    terrain_ecs_edit_stats_info stats = ed->stats;
    stats.queued = (int)ed->queue_count;
    stats.stabilizing_chunks = (int)ed->region_count;
    return stats;
}
