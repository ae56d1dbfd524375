/* grass.c — grass patches (vegetation.h): the GrassPatch component, its placement system and
 * drawing. Placement is grass_place.comp → grass_scan.comp → grass_place.comp on the GPU; the
 * CPU only reads back one count per patch, to size the patch's tuft buffer. */
#include "vegetation.h"
#include "vegetation_internal.h"

#include "core/core.h"
#include "ecs/ecs.h"
#include "gfx/gfx.h"
#include "trace/trace.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define GRASS_GROUP_SIZE 64               /* grass_place.comp's and grass_cull.comp's local size */
#define GRASS_TUFT_BYTES 32               /* two vec4: as placed */
#define GRASS_SHAPED_BYTES 80             /* five vec4: as the culling pass shapes it to draw */
#define GRASS_MAX_LEVEL 1                 /* levels 0 and 1 cover ≥ 64 m around the viewer */
#define GRASS_REACH_AHEAD 32.0            /* patches are placed this far beyond the range … */
#define GRASS_REACH_KEEP 96.0             /* … and released only this far beyond it */
#define GRASS_WAVE_PERIOD 256.0           /* metres after which the gusts repeat */
#define GRASS_MAX_RUNS TERRAIN_MESH_PARTS /* runs of tufts a patch's culling looks at; grass_cull.comp's MAX_RUNS */

struct grass_system {
    grass_system_desc desc;
    gfx_program place, scan, cull, draw;
    gfx_texture blades;
    ecs_component mesh_chunk, patch;
    ecs_query *patches;                   /* TerrainMeshChunk with GrassPatch */
    ecs_system system, cull_system;       /* grass_place, grass_cull */
    gfx_buffer counts, tops;              /* scratch of placement, grown as needed */
    gfx_buffer total;                     /* placement's tuft count, read back to size a patch */
    gfx_buffer visible, command;          /* each frame: the tufts that can show, and their draw */
    gfx_vertex_array corners;             /* no attributes: the two quads' 12 indices */
    gfx_buffer corner_indices;
    float *tops_cpu;
    size_t tops_capacity;
    terrain_view view;
    bool has_view, has_feet;
    double feet[3];
    float sea_level;
    uint32_t seed;
    uint64_t place_ns;
    grass_system_stats_info stats;
};

bool grass_parse_quality(const char *text, grass_quality *out) {
    static const char *const names[] = { "off", "low", "high" };
    for (int q = 0; q < 3; q++)
        if (text && strcmp(text, names[q]) == 0) {
            *out = (grass_quality)(GRASS_OFF + q);
            return true;
        }
    return false;
}

const char *grass_quality_name(grass_quality quality) {
    switch (quality) {
    case GRASS_OFF: return "off";
    case GRASS_HIGH: return "high";
    default: return "low";
    }
}

/* ---- the component's lifetime ---------------------------------------------------------- */

static void grass_patch_release(GrassPatch *patch) {
    gfx_buffer_destroy(&patch->tuft_buffer);
    patch->tufts = 0;
}

/* Whatever removes a patch (the chunk evicted, out of reach, the world destroyed), its buffers
 * go with it. Structural changes happen on the thread that runs ecs_progress: OpenGL's. */
static void grass_patch_removed(ecs_world *world, ecs_entity entity, void *data, void *user) {
    (void)world, (void)entity;
    grass_system *grass = user;
    GrassPatch *patch = data;
    grass->stats.patches--;
    grass->stats.tufts -= patch->tufts;
    grass_patch_release(patch);
}

/* ---- placement ------------------------------------------------------------------------- */

static void grass_buffer_reserve(gfx_buffer *buffer, size_t bytes) {
    if (buffer->id && gfx_buffer_size(*buffer) >= bytes) return;
    gfx_buffer_destroy(buffer);
    size_t size = bytes < 4096 ? 4096 : bytes + bytes / 2;
    *buffer = gfx_buffer_create(&(gfx_buffer_desc){ .size = size, .usage = GFX_BUFFER_DYNAMIC });
}

/* The top of each column under the chunk (terrain_stacks_top): a tuft needs sky above it. */
static int grass_upload_tops(grass_system *g, const TerrainMeshChunk *chunk, float tops_origin[2]) {
    int side = TERRAIN_MESH_CELLS << chunk->lod.level, per = TERRAIN_CHUNK_COLUMNS;
    int64_t first_x = chunk->x * side, first_z = chunk->z * side;
    size_t count = (size_t)side * (size_t)side;
    g->tops_cpu = core_grow(g->tops_cpu, &g->tops_capacity, count, sizeof *g->tops_cpu);
    for (int bz = 0; bz < side / per; bz++)
        for (int bx = 0; bx < side / per; bx++) {
            terrain_chunk_coord coord = { first_x / per + bx, first_z / per + bz };
            const terrain_stacks *stacks = terrain_world_stacks(g->desc.world, coord);
            for (int k = 0; k < per; k++)
                for (int i = 0; i < per; i++)
                    g->tops_cpu[(size_t)(bz * per + k) * (size_t)side + (size_t)(bx * per + i)] =
                        terrain_stacks_top(stacks, i, k);
        }
    grass_buffer_reserve(&g->tops, count * sizeof(float));
    gfx_buffer_update(g->tops, 0, g->tops_cpu, count * sizeof(float));
    tops_origin[0] = (float)(chunk->gpu.origin[0] - (double)first_x);
    tops_origin[1] = (float)(chunk->gpu.origin[2] - (double)first_z);
    return side;
}

static void grass_uniform_uint(GLuint program, const char *name, uint32_t a) {
    glProgramUniform1ui(program, glGetUniformLocation(program, name), a);
}

/* The uniforms of grass_place.comp for one chunk (both runs). */
static void grass_place_uniforms(grass_system *g, const TerrainMeshChunk *chunk, uint32_t triangles,
                                 const float tops_origin[2], int tops_size) {
    gfx_context *gfx = g->desc.gfx;
    GLuint program = gfx_program_gl(gfx, g->place);
    int density = g->desc.density;
    gfx_program_use(gfx, g->place);
    grass_uniform_uint(program, "u_triangle_count", triangles);
    grass_uniform_uint(program, "u_seed", g->seed);
    /* Mesh origins are whole metres (samples sit on the column grid), so the origin's lattice
     * cell is exact; wrapping to 32 bits only repeats the lattice every 2^32 cells. */
    uint32_t cell_x = (uint32_t)((int64_t)llround(chunk->gpu.origin[0]) * density);
    uint32_t cell_z = (uint32_t)((int64_t)llround(chunk->gpu.origin[2]) * density);
    glProgramUniform2ui(program, glGetUniformLocation(program, "u_origin_cell"), cell_x, cell_z);
    gfx_uniform_int(gfx, g->place, "u_density", density);
    gfx_uniform_float(gfx, g->place, "u_origin_y", (float)chunk->gpu.origin[1]);
    gfx_uniform_vec2(gfx, g->place, "u_tops_origin", tops_origin);
    gfx_uniform_int(gfx, g->place, "u_tops_size", tops_size);
    gfx_uniform_float(gfx, g->place, "u_slope_limit", g->desc.slope_limit);
    gfx_uniform_float(gfx, g->place, "u_sea_level", g->sea_level);
    gfx_uniform_float(gfx, g->place, "u_snow_height", g->desc.snow_height);
}

/* Where each of the mesh's parts starts among the tufts: the scan's offset at the part's first
 * triangle (parts are runs of triangles, tufts are placed in triangle order). Read after the
 * total, which already waited for the scan. */
static void grass_part_tufts(grass_system *g, const terrain_gpu_mesh *mesh, GrassPatch *patch) {
    patch->part_count = patch->tufts ? mesh->part_count : 0;
    for (uint32_t p = 0; p < patch->part_count; p++)
        glGetNamedBufferSubData(gfx_buffer_gl(g->counts), (GLintptr)(mesh->parts[p].first_index / 3 * sizeof(uint32_t)),
                                sizeof(uint32_t), &patch->part_first_tuft[p]);
    patch->part_first_tuft[patch->part_count] = patch->tufts;
}

/* Places the chunk's tufts into `patch` (whose buffers are released first). */
static void grass_place(grass_system *g, const TerrainMeshChunk *chunk, GrassPatch *patch) {
    TRACE_ZONE("grass_place_patch");
    gfx_context *gfx = g->desc.gfx;
    grass_patch_release(patch);
    const terrain_gpu_mesh *mesh = &chunk->gpu;
    uint32_t triangles = mesh->index_count / 3;
    patch->source = mesh->serial;
    memcpy(patch->origin, mesh->origin, sizeof patch->origin);
    memcpy(patch->bounds_min, mesh->bounds_min, sizeof patch->bounds_min);
    memcpy(patch->bounds_max, mesh->bounds_max, sizeof patch->bounds_max);
    grass_buffer_reserve(&g->counts, (size_t)triangles * sizeof(uint32_t));
    float tops_origin[2];
    int tops_size = grass_upload_tops(g, chunk, tops_origin);
    grass_place_uniforms(g, chunk, triangles, tops_origin, tops_size);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, gfx_buffer_gl(mesh->vertex_buffer));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, gfx_buffer_gl(mesh->index_buffer));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 2, gfx_buffer_gl(g->counts));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, gfx_buffer_gl(g->tops));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 5, gfx_buffer_gl(g->total));
    GLuint groups = (triangles + GRASS_GROUP_SIZE - 1) / GRASS_GROUP_SIZE;
    gfx_uniform_int(gfx, g->place, "u_write", 0);
    glDispatchCompute(groups, 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    gfx_program_use(gfx, g->scan);
    grass_uniform_uint(gfx_program_gl(gfx, g->scan), "u_triangle_count", triangles);
    glDispatchCompute(1, 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);
    /* The one value the CPU reads: the tufts, to size their buffer (a wait for this chunk's
     * placement, once per placement, never per frame). */
    glGetNamedBufferSubData(gfx_buffer_gl(g->total), 0, sizeof patch->tufts, &patch->tufts);
    grass_part_tufts(g, mesh, patch);
    if (patch->tufts) {
        patch->tuft_buffer = gfx_buffer_create(&(gfx_buffer_desc){ .size = (size_t)patch->tufts * GRASS_TUFT_BYTES });
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 3, gfx_buffer_gl(patch->tuft_buffer));
        gfx_program_use(gfx, g->place);
        gfx_uniform_int(gfx, g->place, "u_write", 1);
        glDispatchCompute(groups, 1, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    }
    for (GLuint binding = 0; binding <= 5; binding++) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, binding, 0);
    g->stats.placements++;
    trace_counter("grass.placed_tufts", (double)patch->tufts);
}

/* Distance from the camera to the chunk's box: in three dimensions, as the tufts fade (a player
 * flying high over a meadow is out of its grass's range, and nothing is placed for it). */
static double grass_box_distance(const grass_system *g, const double origin[3], const float lo[3], const float hi[3]) {
    double squares = 0;
    for (int a = 0; a < 3; a++) {
        double c = g->view.camera[a], min = origin[a] + lo[a], max = origin[a] + hi[a];
        double d = c < min ? min - c : c > max ? c - max : 0.0;
        squares += d * d;
    }
    return sqrt(squares);
}

/* Whether the chunk should have a patch: a shown, uploaded chunk of a fine level near the view
 * (kept a little further than it is placed, so a patch on the edge is not made and dropped in
 * turn). */
static bool grass_wants(const grass_system *g, const TerrainMeshChunk *c, double distance, bool has_patch) {
    if (g->desc.quality == GRASS_OFF || !g->has_view || c->lod.level > GRASS_MAX_LEVEL || c->hidden ||
        c->gpu.index_count == 0)
        return false;
    return distance <= g->desc.range + (has_patch ? GRASS_REACH_KEEP : GRASS_REACH_AHEAD);
}

/* The draw phase, after terrain_upload (it reads what that writes): patches follow the chunks.
 * A chunk re-uploaded after an edit is placed again in this frame, whatever the budget. */
static void grass_place_system(ecs_iter *it) {
    grass_system *g = it->user;
    gfx_context *gfx = g->desc.gfx;
    uint64_t start = core_time_ns();
    int placed = 0;
    bool pass_open = false;
    while (ecs_query_next(it)) {
        TerrainMeshChunk *chunks = ecs_field(it, 0);
        GrassPatch *patches = ecs_field(it, 1);
        for (int i = 0; i < it->count; i++) {
            TerrainMeshChunk *c = &chunks[i];
            GrassPatch *patch = patches ? &patches[i] : NULL;
            double distance = grass_box_distance(g, c->gpu.origin, c->gpu.bounds_min, c->gpu.bounds_max);
            bool wanted = grass_wants(g, c, distance, patch != NULL);
            if (patch && !wanted) ecs_defer_remove(it->commands, it->entities[i], g->patch);
            if (!wanted || (patch && patch->source == c->gpu.serial)) continue;
            /* The budget spreads the patches placed ahead of need over frames; a chunk already in
             * range (one that replaced a coarser chunk around the player) is placed at once, or
             * its ground would show bare until the budget came round to it. */
            if (!patch && distance > g->desc.range && placed >= g->desc.max_placements) continue;
            if (!pass_open) gfx_pass_begin(gfx, &(gfx_pass_desc){ .name = "grass.place" });
            pass_open = true;
            if (patch) {
                g->stats.tufts -= patch->tufts;
                grass_place(g, c, patch);
                g->stats.tufts += patch->tufts;
                continue;
            }
            GrassPatch fresh = { 0 };
            grass_place(g, c, &fresh);
            /* Counted once the component is on the entity (the hook takes it off again). */
            ecs_defer_set(it->commands, it->entities[i], g->patch, &fresh);
            g->stats.patches++;
            g->stats.tufts += fresh.tufts;
            placed++;
        }
    }
    if (pass_open) gfx_pass_end(gfx);
    g->place_ns += core_time_ns() - start;
    trace_counter("grass.patches", (double)g->stats.patches);
    trace_counter("grass.tufts", (double)g->stats.tufts);
}

/* ---- the system ------------------------------------------------------------------------ */

static void grass_cull_system(ecs_iter *it);      /* with the drawing, below */

static void grass_defaults(grass_system_desc *d) {
    bool high = d->quality == GRASS_HIGH;
    if (d->quality == GRASS_DEFAULT) d->quality = GRASS_LOW;
    if (d->density <= 0) d->density = high ? 3 : 2;
    if (d->density > 8) d->density = 8;
    if (!(d->range > 0)) d->range = high ? 70.0f : 35.0f;
    if (!(d->slope_limit > 0)) d->slope_limit = 35.0f;
    if (!(d->height > 0)) d->height = 0.5f;
    if (d->snow_height == 0) d->snow_height = 120.0f;
    if (d->fog_density == 0) d->fog_density = 0.0025f;
    if (d->max_placements <= 0) d->max_placements = 4;
}

grass_system *grass_system_create(const grass_system_desc *desc) {
    if (!desc || !desc->gfx || !desc->ecs || !desc->world) {
        core_log_error("grass", "grass_system_create needs .gfx, .ecs and .world");
        return NULL;
    }
    ecs_component mesh_chunk = ecs_component_lookup(desc->ecs, "TerrainMeshChunk");
    if (!mesh_chunk) {
        core_log_error("grass", "no TerrainMeshChunk in this ECS world: call terrain_ecs_create first");
        return NULL;
    }
    gfx_program place = gfx_program_load_compute(desc->gfx, "grass_place.comp");
    gfx_program scan = gfx_program_load_compute(desc->gfx, "grass_scan.comp");
    gfx_program cull = gfx_program_load_compute(desc->gfx, "grass_cull.comp");
    gfx_program draw = gfx_program_load(desc->gfx, "grass.vert", "grass.frag");
    if (!place.id || !scan.id || !cull.id || !draw.id) return NULL;
    grass_system *g = core_calloc(1, sizeof *g);
    g->desc = *desc;
    grass_defaults(&g->desc);
    g->place = place, g->scan = scan, g->cull = cull, g->draw = draw;
    g->total = gfx_buffer_create(&(gfx_buffer_desc){ .size = sizeof(uint32_t), .usage = GFX_BUFFER_DYNAMIC });
    g->command = gfx_buffer_create(&(gfx_buffer_desc){ .size = 5 * sizeof(uint32_t), .usage = GFX_BUFFER_DYNAMIC });
    static const uint32_t quads[12] = { 0, 1, 2, 2, 1, 3, 4, 5, 6, 6, 5, 7 };   /* corners as grass.vert numbers them */
    g->corner_indices = gfx_buffer_create(&(gfx_buffer_desc){ .size = sizeof quads, .data = quads });
    g->corners = gfx_vertex_array_create(&(gfx_vertex_array_desc){ .indices = g->corner_indices });
    const terrain_generation_desc *generation = terrain_world_generation(desc->world);
    g->sea_level = generation->sea_level;
    g->seed = (uint32_t)core_hash_u64(generation->seed ^ 0x6772617373ull);   /* "grass" */
    g->blades = grass__blade_texture();
    g->mesh_chunk = mesh_chunk;
    g->patch = ECS_COMPONENT(desc->ecs, GrassPatch);
    ecs_component_on_remove(desc->ecs, g->patch, grass_patch_removed, g);
    g->patches = ecs_query_create(desc->ecs, &(ecs_query_desc){ .with = { mesh_chunk, g->patch } });
    g->stats.patches = ecs_query_count(desc->ecs, g->patches);   /* left empty by an earlier system */
    g->system = ecs_system_add(desc->ecs, &(ecs_system_desc){ .name = "grass_place", .phase = "draw",
        .query = { .with = { mesh_chunk }, .optional = { g->patch } }, .writes = { g->patch },
        .fn = grass_place_system, .user = g, .main_thread = true });
    g->cull_system = ecs_system_add(desc->ecs, &(ecs_system_desc){ .name = "grass_cull", .phase = "draw",
        .query = { .with = { mesh_chunk, g->patch } }, .writes = { g->patch },
        .fn = grass_cull_system, .user = g, .main_thread = true });
    return g;
}

void grass_system_destroy(grass_system *g) {
    if (!g) return;
    /* The hook and the system would outlive `g` in the world: release the patches here (a
     * released patch is empty, source 0: a later grass_system_create places it again), unhook, and
     * disable the system. */
    ecs_component_on_remove(g->desc.ecs, g->patch, NULL, NULL);
    ecs_system_enable(g->desc.ecs, g->system, false);
    ecs_system_enable(g->desc.ecs, g->cull_system, false);
    ecs_iter it = ecs_query_iter(g->desc.ecs, g->patches);
    while (ecs_query_next(&it)) {
        GrassPatch *patches = ecs_field(&it, 1);
        for (int i = 0; i < it.count; i++) {
            grass_patch_release(&patches[i]);
            patches[i].source = 0;
        }
    }
    gfx_buffer_destroy(&g->counts);
    gfx_buffer_destroy(&g->tops);
    gfx_buffer_destroy(&g->total);
    gfx_buffer_destroy(&g->visible);
    gfx_buffer_destroy(&g->command);
    gfx_vertex_array_destroy(&g->corners);
    gfx_buffer_destroy(&g->corner_indices);
    core_free(g->tops_cpu, g->tops_capacity * sizeof *g->tops_cpu);
    gfx_texture_destroy(&g->blades);
    core_free(g, sizeof *g);
}

void grass_set_view(grass_system *g, const terrain_view *view, const double player_feet[3]) {
    g->view = *view;
    g->has_view = true;
    g->has_feet = player_feet != NULL;
    if (player_feet) memcpy(g->feet, player_feet, sizeof g->feet);
}

/* ---- drawing ----------------------------------------------------------------------------
 *
 * Each frame: grass_cull.comp over every patch worth drawing appends the tufts that can show to
 * one buffer (camera-relative), then one indirect draw of them all. The CPU sets a few uniforms
 * per patch and never learns the count. */

static double grass_wrap(double value, double period) { return value - floor(value / period) * period; }

/* Whether the patch is drawn this frame: its chunk visible, its box within the range. */
static bool grass_patch_drawn(const grass_system *g, const TerrainMeshChunk *chunk, const GrassPatch *p) {
    return p->tufts && chunk->visible && grass_box_distance(g, p->origin, p->bounds_min, p->bounds_max) <= g->desc.range;
}

/* What shapes a tuft in grass_cull.comp: the wind's clock and place, and the player's feet. */
static void grass_shape_uniforms(grass_system *g, const terrain_view *view) {
    gfx_context *gfx = g->desc.gfx;
    float player[3] = { 0, -1e6f, 0 };           /* nothing bends */
    if (g->has_feet)
        for (int a = 0; a < 3; a++) player[a] = (float)(g->feet[a] - view->camera[a]);
    float camera_wave[2] = { (float)grass_wrap(view->camera[0], GRASS_WAVE_PERIOD),
                             (float)grass_wrap(view->camera[2], GRASS_WAVE_PERIOD) };
    float sun[3];
    const float zero[3] = { 0, 0, 0 };
    terrain_view_sun(view, sun);
    gfx_uniform_vec3(gfx, g->cull, "u_sun_direction", sun);
    gfx_uniform_vec3(gfx, g->cull, "u_camera_position", zero);
    gfx_uniform_float(gfx, g->cull, "u_fog_density", g->desc.fog_density);
    gfx_uniform_vec3(gfx, g->cull, "u_player", player);
    gfx_uniform_vec2(gfx, g->cull, "u_camera_wave", camera_wave);
    gfx_uniform_float(gfx, g->cull, "u_time", view->time);
}

/* The runs of the patch's tufts that can show: those of the mesh's parts whose box, grown by
 * what a tuft reaches from its root (1.7 heights up, 1.2 around: grass_cull.comp's sphere, for
 * the tallest tuft, 1.4 × the average height), is in the frustum and whose roots' box is within
 * the range. Adjacent parts make one run. `first[r]` is run r's first tuft, `start[r]` the
 * tufts of the runs before it (start[runs]: all). Returns the runs. The shader still tests each
 * tuft: the parts only spare it the tufts that cannot pass. */
static int grass_runs(const grass_system *g, const TerrainMeshChunk *chunk, const GrassPatch *p,
                      const terrain_frustum *frustum, uint32_t first[GRASS_MAX_RUNS], uint32_t start[GRASS_MAX_RUNS + 1]) {
    start[0] = 0;
    if (p->part_count == 0 || chunk->gpu.serial != p->source || chunk->gpu.part_count != p->part_count) {
        first[0] = 0, start[1] = p->tufts;
        return 1;
    }
    const float reach = 2.4f * g->desc.height;
    int runs = 0;
    bool open = false;                   /* the last part was in a run */
    for (uint32_t k = 0; k < p->part_count; k++) {
        const terrain_mesh_part *part = &chunk->gpu.parts[k];
        float lo[3], hi[3];
        for (int a = 0; a < 3; a++) lo[a] = part->bounds_min[a] - reach, hi[a] = part->bounds_max[a] + reach;
        bool in = p->part_first_tuft[k + 1] > p->part_first_tuft[k] && terrain_frustum_sees(frustum, p->origin, lo, hi) &&
                  grass_box_distance(g, p->origin, part->bounds_min, part->bounds_max) <= g->desc.range;
        if (in && !open) first[runs] = p->part_first_tuft[k], start[runs + 1] = start[runs], runs++;
        if (in) start[runs] += p->part_first_tuft[k + 1] - p->part_first_tuft[k];
        open = in;
    }
    return runs;
}

/* Appends the tufts of the patches in view to g->visible; returns the tufts looked at. It runs
 * in the draw phase, before anything of the frame is drawn: the barrier that makes its results
 * visible to the draw then waits for nothing (after the terrain's draws it would wait for them:
 * llvmpipe finishes every pending draw there). */
static uint64_t grass_cull(grass_system *g, const terrain_view *view) {
    gfx_context *gfx = g->desc.gfx;
    uint64_t considered = 0;
    ecs_iter it = ecs_query_iter(g->desc.ecs, g->patches);
    while (ecs_query_next(&it)) {
        const TerrainMeshChunk *chunks = ecs_field(&it, 0);
        const GrassPatch *patches = ecs_field(&it, 1);
        for (int i = 0; i < it.count; i++)
            if (grass_patch_drawn(g, &chunks[i], &patches[i])) considered += patches[i].tufts;
    }
    if (!considered) return 0;
    grass_buffer_reserve(&g->visible, (size_t)considered * GRASS_SHAPED_BYTES);
    const uint32_t reset[5] = { 12, 0, 0, 0, 0 };         /* two crossed quads, no tuft yet */
    gfx_buffer_update(g->command, 0, reset, sizeof reset);
    terrain_frustum frustum = terrain_frustum_from_view(view);
    GLuint program = gfx_program_gl(gfx, g->cull);
    gfx_program_use(gfx, g->cull);
    glProgramUniform4fv(program, glGetUniformLocation(program, "u_planes"), 6, &frustum.planes[0][0]);
    gfx_uniform_float(gfx, g->cull, "u_range", g->desc.range);
    gfx_uniform_float(gfx, g->cull, "u_height", g->desc.height);
    grass_shape_uniforms(g, view);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 5, gfx_buffer_gl(g->command));
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 6, gfx_buffer_gl(g->visible));
    GLint run_count = glGetUniformLocation(program, "u_run_count");
    GLint run_first = glGetUniformLocation(program, "u_run_first"), run_start = glGetUniformLocation(program, "u_run_start");
    uint64_t looked = 0;
    it = ecs_query_iter(g->desc.ecs, g->patches);
    while (ecs_query_next(&it)) {
        const TerrainMeshChunk *chunks = ecs_field(&it, 0);
        const GrassPatch *patches = ecs_field(&it, 1);
        for (int i = 0; i < it.count; i++) {
            const GrassPatch *p = &patches[i];
            if (!grass_patch_drawn(g, &chunks[i], p)) continue;
            uint32_t first[GRASS_MAX_RUNS], start[GRASS_MAX_RUNS + 1];
            int runs = grass_runs(g, &chunks[i], p, &frustum, first, start);
            if (start[runs] == 0) continue;   /* no run, or only empty ones */
            float offset[3];
            for (int a = 0; a < 3; a++) offset[a] = (float)(p->origin[a] - view->camera[a]);
            gfx_uniform_vec3(gfx, g->cull, "u_offset", offset);
            grass_uniform_uint(program, "u_tuft_count", start[runs]);
            glProgramUniform1i(program, run_count, runs);
            glProgramUniform1uiv(program, run_first, runs, first);
            glProgramUniform1uiv(program, run_start, runs + 1, start);
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, gfx_buffer_gl(p->tuft_buffer));
            glDispatchCompute((start[runs] + GRASS_GROUP_SIZE - 1) / GRASS_GROUP_SIZE, 1, 1);
            looked += start[runs];
            g->stats.patches_drawn++;
        }
    }
    for (GLuint binding = 0; binding <= 6; binding++) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, binding, 0);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);
    return looked;
}

static void grass_draw_uniforms(grass_system *g, const terrain_view *view) {
    gfx_context *gfx = g->desc.gfx;
    float view_projection[16];
    terrain_view_matrix(view, view_projection);
    gfx_program_use(gfx, g->draw);
    gfx_uniform_mat4(gfx, g->draw, "u_view_projection", view_projection);
    gfx_uniform_int(gfx, g->draw, "u_blades", 0);
    gfx_texture_bind(g->blades, 0);
}

/* The draw phase, after grass_place: the frame's tufts in view, ready for grass_draw. */
static void grass_cull_system(ecs_iter *it) {
    grass_system *g = it->user;
    uint64_t start = core_time_ns();
    g->stats.patches_drawn = 0;
    g->stats.tufts_drawn = 0;
    if (g->has_view && g->stats.patches > 0) {
        gfx_pass_begin(g->desc.gfx, &(gfx_pass_desc){ .name = "grass.cull" });
        g->stats.tufts_drawn = grass_cull(g, &g->view);
        gfx_pass_end(g->desc.gfx);
        trace_counter("grass.tufts_culled", (double)g->stats.tufts_drawn);
    }
    g->place_ns += core_time_ns() - start;
}

void grass_draw(grass_system *g, const terrain_view *view) {
    uint64_t start = core_time_ns();
    if (g->desc.quality != GRASS_OFF) {
        gfx_context *gfx = g->desc.gfx;
        if (g->stats.tufts_drawn) {
            gfx_pass_begin(gfx, &(gfx_pass_desc){ .name = "grass" });
            grass_draw_uniforms(g, view);
            glDisable(GL_CULL_FACE);             /* a billboard is seen from both sides */
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, gfx_buffer_gl(g->visible));
            gfx_draw(&(gfx_draw_desc){ .vertex_array = g->corners, .index_type = GFX_INDEX_U32,
                                       .indirect = g->command });
            glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, 0);
            glEnable(GL_CULL_FACE);
            gfx_pass_end(gfx);
        }
    }
    g->stats.cpu_ms = (double)(g->place_ns + (core_time_ns() - start)) * 1e-6;
    g->place_ns = 0;
}

uint64_t grass_visible_tufts(grass_system *g) {
    if (!g->stats.tufts_drawn) return 0;
    uint32_t command[5];
    glGetNamedBufferSubData(gfx_buffer_gl(g->command), 0, sizeof command, command);
    return command[1];
}

grass_system_stats_info grass_system_stats(const grass_system *g) {
    grass_system_stats_info s = g->stats;
    s.bytes = (size_t)s.tufts * GRASS_TUFT_BYTES;
    return s;
}

/* ---- reading back (tests, tools) -------------------------------------------------------- */

typedef struct grass_digest_item { int64_t x, y, z, level; uint64_t hash; } grass_digest_item;   /* no padding */

static int grass_digest_compare(const void *a, const void *b) {
    const grass_digest_item *p = a, *q = b;
    if (p->level != q->level) return p->level < q->level ? -1 : 1;
    if (p->y != q->y) return p->y < q->y ? -1 : 1;
    if (p->z != q->z) return p->z < q->z ? -1 : 1;
    return (p->x > q->x) - (p->x < q->x);
}

uint64_t grass_tufts_digest(grass_system *g) {
    grass_digest_item *items = NULL;
    size_t count = 0, capacity = 0;
    ecs_iter it = ecs_query_iter(g->desc.ecs, g->patches);
    while (ecs_query_next(&it)) {
        const TerrainMeshChunk *chunks = ecs_field(&it, 0);
        const GrassPatch *patches = ecs_field(&it, 1);
        for (int i = 0; i < it.count; i++) {
            size_t bytes = (size_t)patches[i].tufts * GRASS_TUFT_BYTES;
            uint64_t hash = core_hash_u64(patches[i].tufts);
            if (bytes) {
                void *data = core_alloc(bytes);
                glGetNamedBufferSubData(gfx_buffer_gl(patches[i].tuft_buffer), 0, (GLsizeiptr)bytes, data);
                hash = core_hash_bytes(data, bytes, hash);
                core_free(data, bytes);
            }
            items = core_grow(items, &capacity, count + 1, sizeof *items);
            items[count++] = (grass_digest_item){ chunks[i].x, chunks[i].y, chunks[i].z, chunks[i].lod.level, hash };
        }
    }
    qsort(items, count, sizeof *items, grass_digest_compare);
    uint64_t digest = core_hash_u64(count);
    for (size_t i = 0; i < count; i++) digest = core_hash_combine(digest, core_hash_bytes(&items[i], sizeof items[i], 7));
    core_free(items, capacity * sizeof *items);
    return digest;
}
