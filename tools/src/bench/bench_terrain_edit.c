/* bench_terrain_edit.c — a sculpt stroke in a running world, from the tool to the updated
 * meshes on the GPU (issue 6's terrain.edit.brush; target ≤ 8 ms).
 *
 * The world is the game's: seed 42, streamed with the default rings around a viewer, headless
 * (OSMesa) so that uploads are real. A sample queues one stroke (terrain_ecs_edit) where the
 * view ray meets the ground in front of the viewer and times the one frame (ecs_progress) that
 * applies it, stabilizes the touched chunks, meshes again every mesh chunk that reads them and
 * uploads those meshes. Strokes alternate add and carve and step along x, so each lands on
 * ground the previous ones changed.
 *
 * Rows:
 *   terrain.edit.brush              ms of the frame with a stroke (R = 2.5 m, the game's sculpt)
 *   terrain.edit.brush.idle_frame   ms of a frame without one, same place (streaming settled)
 *   terrain.edit.brush.chunks       mesh chunks meshed again per stroke
 */
#include "bench.h"

#include "core/core.h"
#include "ecs/ecs.h"
#include "gfx/gfx.h"
#include "jobs/jobs.h"
#include "terrain/terrain.h"

#include <math.h>
#include <time.h>

typedef struct edit_bench {
    ecs_world *ecs;
    terrain_world *world;
    terrain_ecs *te;
    double eye[3];
    int strokes;
    double chunks[32];                /* mesh chunks meshed again, per stroke */
} edit_bench;

/* Frames until streaming and stabilization have nothing left, or `seconds` pass. Between frames
 * the main thread sleeps a millisecond, as a frame's drawing would let the workers get on. */
static bool edit_bench_settle(edit_bench *b, double seconds) {
    uint64_t deadline = core_time_ns() + (uint64_t)(seconds * 1e9);
    while (core_time_ns() < deadline) {
        terrain_ecs_set_viewers(b->te, (const double (*)[3])b->eye, 1);
        ecs_progress(b->ecs, 1.0f / 60.0f);
        terrain_world_trim(b->world);
        terrain_ecs_stream_stats_info s = terrain_ecs_stream_stats(b->te);
        if (s.mesh_chunks_wanted > 0 && s.mesh_chunks_ready == s.mesh_chunks_wanted && s.jobs_in_flight == 0 &&
            terrain_ecs_edit_stats(b->te).stabilizing_chunks == 0)
            return true;
        nanosleep(&(struct timespec){ 0, 1000000 }, NULL);
    }
    return false;
}

static double edit_bench_frame(edit_bench *b) {
    terrain_ecs_set_viewers(b->te, (const double (*)[3])b->eye, 1);
    uint64_t start = core_time_ns();
    ecs_progress(b->ecs, 1.0f / 60.0f);
    double ms = (double)(core_time_ns() - start) * 1e-6;
    terrain_world_trim(b->world);
    return ms;
}

static double sample_stroke(void *user) {
    edit_bench *b = user;
    int n = b->strokes++;
    /* Down and ahead at 30°, stepping 1.5 m along x per stroke. */
    double origin[3] = { b->eye[0] + 1.5 * (n % 8) - 6.0, b->eye[1], b->eye[2] };
    float direction[3] = { 0.0f, -0.5f, -0.8660254f };
    terrain_ray_hit hit;
    if (!terrain_raycast(b->world, origin, direction, 200.0f, &hit)) return NAN;
    terrain_ecs_edit(b->te, &(terrain_edit){
        .tool = n % 2 ? TERRAIN_EDIT_SCULPT_CARVE : TERRAIN_EDIT_SCULPT_ADD,
        .sculpt = { .target = { hit.position[0], hit.position[1], hit.position[2] }, .radius = 2.5f } });
    uint64_t meshed = terrain_ecs_stream_stats(b->te).chunks_meshed + terrain_ecs_stream_stats(b->te).chunks_skipped_empty;
    double ms = edit_bench_frame(b);
    uint64_t after = terrain_ecs_stream_stats(b->te).chunks_meshed + terrain_ecs_stream_stats(b->te).chunks_skipped_empty;
    if (n < 32) b->chunks[n] = (double)(after - meshed);
    edit_bench_settle(b, 10.0);            /* nothing left over for the next sample */
    return ms;
}

static double sample_idle(void *user) { return edit_bench_frame(user); }

void bench_group_terrain_edit(bench_context *ctx) {
    if (!bench_wants(ctx, "terrain.edit.brush")) return;
    gfx_context *gfx = gfx_context_create(&(gfx_context_desc){ .width = 64, .height = 64, .headless = true, .title = "bench" });
    if (!gfx) {
        core_log_error("bench", "terrain.edit.brush: no offscreen context; rows skipped");
        return;
    }
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = bench_threads(ctx) });
    edit_bench b = { .ecs = ecs_world_create(&(ecs_world_desc){ .jobs = jobs }) };
    b.world = terrain_world_create(&(terrain_world_desc){ .generation = terrain_generation_defaults(42) });
    b.te = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = b.ecs, .terrain = b.world });
    terrain_ecs_stream(b.te, &(terrain_stream_desc){ 0 });
    b.eye[0] = 16, b.eye[2] = 16;
    b.eye[1] = terrain_stacks_top(terrain_world_stacks(b.world, (terrain_chunk_coord){ 0, 0 }), 16, 16) + 12.0;
    if (edit_bench_settle(&b, 300.0)) {
        bench_run(ctx, "terrain.edit.brush.idle_frame", "ms", 15, sample_idle, &b);
        /* bench_run makes one warm-up call: 16 strokes, the last 15 timed. */
        bench_run(ctx, "terrain.edit.brush", "ms", 15, sample_stroke, &b);
        bench_record(ctx, "terrain.edit.brush.chunks", "chunks", b.chunks + 1, 15);
    } else {
        core_log_error("bench", "terrain.edit.brush: the world never settled; rows skipped");
    }
    terrain_ecs_destroy(b.te);
    ecs_world_destroy(b.ecs);
    terrain_world_destroy(b.world);
    job_system_destroy(jobs);
    gfx_context_destroy(gfx);
}
