/* bench_world_seam.c — the seam between the volumetric chunks and the far clipmap (002 §3.5),
 * on the CPU, in the game's fixed configuration: seed 1, rings of 3 levels with half width 2
 * (the hole is the 512 m square of the outermost, level-2 ring, centred on the viewer snapped
 * to 128 m), the default clipmap (6 levels of 128² cells from 4 m).
 *
 * Nine views 256 m apart along x from the origin (2 km). At each, the level-2 mesh chunks along
 * the hole's border are meshed as the streamer meshes them (terrain_mesh_chunk), and at every
 * one of their samples on the border (4 m apart) the topmost vertex on the sample's vertical
 * line is the chunks' surface; the gap is its distance to terrain_clipmap_height there (the
 * clipmap's finest level at the point, morphed as drawn; on the border the pit has not begun).
 * Two clipmaps in the same run: one made with the world (heights from the stacks where chunks
 * are cached, desc.mesh_step 4 for the level-2 meshes) and one with G alone, as before.
 *
 *   world.seam.max_gap          m, the largest gap over all views' border samples (target ≤ 0.25)
 *   world.seam.median_gap       m, the median gap
 *   world.seam.max_gap.g_only   m, the largest gap with the clipmap on G alone (the old way)
 *   world.seam.median_gap.g_only
 */
#include "bench.h"

#include "core/core.h"
#include "jobs/jobs.h"
#include "terrain/terrain.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define SEAM_LEVELS 3
#define SEAM_HALF_WIDTH 2
#define SEAM_VIEWS 9
#define SEAM_MAX_MESHES 64

typedef struct seam_mesh_task {
    int64_t x, y, z;
    terrain_mesh mesh;
    bool ok;
} seam_mesh_task;

#define SEAM_MAX_BETWEEN 65536

/* A mesh vertex on the border between two samples (n and n + 1 along its side). */
typedef struct seam_between {
    double x, y, z;
    size_t sample;
    bool last;                      /* n is its side's last sample: no n + 1 on the side */
} seam_between;

typedef struct seam_state {
    terrain_world *world;
    seam_between between[SEAM_MAX_BETWEEN];
    size_t between_count;
    seam_mesh_task tasks[SEAM_MAX_MESHES];
    int task_count;
} seam_state;

static void mesh_range(void *user, size_t begin, size_t end) {
    seam_state *s = user;
    for (size_t t = begin; t < end; t++) {
        seam_mesh_task *task = &s->tasks[t];
        task->ok = terrain_mesh_chunk(s->world, task->x, task->y, task->z, &(terrain_lod_desc){ .level = SEAM_LEVELS - 1 },
                                      &task->mesh);
    }
}

static int compare_doubles(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median_of(double *values, size_t count) {
    if (count == 0) return NAN;
    qsort(values, count, sizeof *values, compare_doubles);
    return values[count / 2];
}

/* One view: the border's samples' mesh tops, compared with both clipmaps; gaps appended. */
static void seam_view(seam_state *s, job_system *jobs, terrain_clipmap *stacks, terrain_clipmap *ground, double x, double z,
                      double *gaps, double *gaps_ground, size_t *count, double *between, size_t *between_count,
                      size_t capacity) {
    const double chunk = (double)TERRAIN_MESH_CELLS * (1 << (SEAM_LEVELS - 1)), step = chunk / TERRAIN_MESH_CELLS;
    int64_t centre[2] = { (int64_t)floor(x / chunk + 0.5), (int64_t)floor(z / chunk + 0.5) };
    double lo[2], hi[2];
    for (int a = 0; a < 2; a++) {
        lo[a] = (double)(centre[a] - SEAM_HALF_WIDTH) * chunk;
        hi[a] = (double)(centre[a] + SEAM_HALF_WIDTH) * chunk;
    }
    /* The border's samples and the mesh chunks that hold them (y: around their columns' tops). */
    int sides = (int)((hi[0] - lo[0]) / step);
    size_t samples = 4 * (size_t)sides;
    double (*points)[2] = core_alloc(samples * sizeof *points);
    float *mesh_top = core_alloc(samples * sizeof *mesh_top);
    s->task_count = 0;
    s->between_count = 0;
    for (size_t n = 0; n < samples; n++) {
        int side = (int)(n / (size_t)sides);
        double t = (double)(n % (size_t)sides) * step;
        points[n][0] = side < 2 ? lo[0] + t : (side == 2 ? lo[0] : hi[0]);
        points[n][1] = side < 2 ? (side == 0 ? lo[1] : hi[1]) : lo[1] + t;
        mesh_top[n] = NAN;
        /* The mesh chunk inside the hole that has this sample on its border face. */
        int64_t cx = (int64_t)floor(points[n][0] / chunk) - (side == 3), cz = (int64_t)floor(points[n][1] / chunk) - (side == 1);
        float top = terrain_world_top(s->world, points[n][0] + 0.5, points[n][1] + 0.5);
        for (int64_t cy = (int64_t)floor((top - 2.0 * step) / chunk); cy <= (int64_t)floor((top + 2.0 * step) / chunk); cy++) {
            bool seen = false;
            for (int t2 = 0; t2 < s->task_count && !seen; t2++)
                seen = s->tasks[t2].x == cx && s->tasks[t2].y == cy && s->tasks[t2].z == cz;
            if (!seen && s->task_count < SEAM_MAX_MESHES) s->tasks[s->task_count++] = (seam_mesh_task){ .x = cx, .y = cy, .z = cz };
        }
    }
    job_parallel_for(jobs, (size_t)s->task_count, 1, mesh_range, s, "bench.seam.mesh");
    for (int t = 0; t < s->task_count; t++) {
        seam_mesh_task *task = &s->tasks[t];
        if (!task->ok) continue;
        for (uint32_t v = 0; v < task->mesh.vertex_count; v++) {
            const float *p = task->mesh.vertices[v].position;
            double vx = task->mesh.origin[0] + p[0], vy = task->mesh.origin[1] + p[1], vz = task->mesh.origin[2] + p[2];
            int side = vz == lo[1] ? 0 : vz == hi[1] ? 1 : vx == lo[0] ? 2 : vx == hi[0] ? 3 : -1;
            if (side < 0) continue;
            double along = side < 2 ? vx - lo[0] : vz - lo[1];
            if (along < 0 || along >= hi[0] - lo[0]) continue;
            size_t n = (size_t)side * (size_t)sides + (size_t)(along / step);
            if (fmod(along, step) != 0.0) {
                /* Between samples: a horizontal edge's crossing in the border's plane. */
                if (s->between_count < SEAM_MAX_BETWEEN) {
                    s->between[s->between_count] = (seam_between){ .x = vx, .y = vy, .z = vz, .sample = n,
                                                                   .last = (n + 1) % (size_t)sides == 0 };
                    s->between_count++;
                }
                continue;
            }
            /* A vertical edge's crossing at a border sample: the topmost is the surface. */
            if (!(vy <= mesh_top[n])) mesh_top[n] = (float)vy;
        }
        terrain_mesh_free(&task->mesh);
    }
    /* The clipmaps after the chunks came (the streamer's next frame). */
    double camera[3] = { x, terrain_world_top(s->world, x, z) + 2.0, z };
    terrain_clipmap_update(stacks, camera);
    terrain_clipmap_update(ground, camera);
    terrain_clipmap_set_hole(stacks, lo, hi);
    terrain_clipmap_set_hole(ground, lo, hi);
    for (size_t n = 0; n < samples && *count < capacity; n++) {
        if (isnan(mesh_top[n])) continue;
        gaps[*count] = fabs(mesh_top[n] - terrain_clipmap_height(stacks, points[n][0], points[n][1]));
        gaps_ground[*count] = fabs(mesh_top[n] - terrain_clipmap_height(ground, points[n][0], points[n][1]));
        (*count)++;
    }
    /* Between samples, the vertices of the topmost contour: those between its two samples'
     * heights (the surface there; lower contours are caves and overhangs' undersides). */
    for (size_t b = 0; b < s->between_count && *between_count < capacity; b++) {
        const seam_between *v = &s->between[b];
        if (v->last) continue;
        float a = mesh_top[v->sample], c = mesh_top[v->sample + 1];
        if (isnan(a) || isnan(c) || v->y < fmin(a, c) - 1e-3 || v->y > fmax(a, c) + 1e-3) continue;
        between[(*between_count)++] = fabs(v->y - terrain_clipmap_height(stacks, v->x, v->z));
    }
    core_free(points, samples * sizeof *points);
    core_free(mesh_top, samples * sizeof *mesh_top);
}

void bench_group_world_seam(bench_context *ctx) {
    if (!bench_wants(ctx, "world.seam")) return;
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = bench_threads(ctx) });
    terrain_generation_desc generation = terrain_generation_defaults(1);
    seam_state *s = core_calloc(1, sizeof *s);
    s->world = terrain_world_create(&(terrain_world_desc){ .generation = generation, .max_chunks = 16384 });
    terrain_clipmap *stacks = terrain_clipmap_create(&(terrain_clipmap_desc){
        .generation = generation, .jobs = jobs, .world = s->world, .mesh_step = (float)(1 << (SEAM_LEVELS - 1)),
        .centre_snap = (float)(TERRAIN_MESH_CELLS << (SEAM_LEVELS - 1)) });
    terrain_clipmap *ground = terrain_clipmap_create(&(terrain_clipmap_desc){ .generation = generation, .jobs = jobs });
    size_t capacity = 4 * SEAM_VIEWS * 4 * 4 * SEAM_HALF_WIDTH * TERRAIN_MESH_CELLS, count = 0;   /* room for the vertices between samples too */
    size_t between_count = 0;
    double *gaps = core_alloc(capacity * sizeof *gaps), *gaps_ground = core_alloc(capacity * sizeof *gaps_ground);
    double *between = core_alloc(capacity * sizeof *between);
    for (int v = 0; v < SEAM_VIEWS; v++)
        seam_view(s, jobs, stacks, ground, 256.0 * v, 0.0, gaps, gaps_ground, &count, between, &between_count, capacity);
    double max_gap = 0, max_ground = 0, max_between = 0;
    for (size_t n = 0; n < between_count; n++) max_between = fmax(max_between, between[n]);
    for (size_t n = 0; n < count; n++) {
        max_gap = fmax(max_gap, gaps[n]);
        max_ground = fmax(max_ground, gaps_ground[n]);
    }
    double median = median_of(gaps, count), median_ground = median_of(gaps_ground, count);
    double median_between = median_of(between, between_count);
    core_log(CORE_LOG_INFO, "bench", "world.seam: %zu border samples and %zu mesh vertices between them over %d views",
             count, between_count, SEAM_VIEWS);
    bench_record(ctx, "world.seam.max_gap", "m", &max_gap, 1);
    bench_record(ctx, "world.seam.median_gap", "m", &median, 1);
    bench_record(ctx, "world.seam.max_gap.between", "m", &max_between, 1);
    bench_record(ctx, "world.seam.median_gap.between", "m", &median_between, 1);
    bench_record(ctx, "world.seam.max_gap.g_only", "m", &max_ground, 1);
    bench_record(ctx, "world.seam.median_gap.g_only", "m", &median_ground, 1);
    core_free(gaps, capacity * sizeof *gaps);
    core_free(gaps_ground, capacity * sizeof *gaps_ground);
    core_free(between, capacity * sizeof *between);
    terrain_clipmap_destroy(ground);
    terrain_clipmap_destroy(stacks);
    terrain_world_destroy(s->world);
    core_free(s, sizeof *s);
    job_system_destroy(jobs);
}
