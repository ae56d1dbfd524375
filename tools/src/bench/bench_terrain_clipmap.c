/* bench_terrain_clipmap.c — the far terrain's geometry clipmap (002 §3.2) on the CPU.
 *
 *   terrain.clipmap.build         ms to fill every level from scratch: the default clipmap (6
 *       levels of 128² cells from 4 m, 6 × 131² heights of G with the octaves each spacing
 *       carries) of seed 42's world, on the job system with bench_threads() threads. Each run
 *       jumps 100 km, so every height is new.
 *   terrain.clipmap.update_step   ms per update of a walk: the camera moves 4 m (one finest
 *       spacing) between updates, diagonally; level 0 moves every 8 m, level L every 2^(L+3) m,
 *       and only the heights that come in are computed. Averaged over a 512 m walk.
 *   terrain.clipmap.triangles     triangles drawn from 60 m above the ground looking level
 *       (60° field, 16:9, 4 km far plane) after culling the blocks: what a frame costs the GPU.
 */
#include "bench.h"

#include "core/core.h"
#include "jobs/jobs.h"
#include "terrain/terrain.h"

typedef struct clipmap_bench {
    terrain_clipmap *clipmap;
    int run;
    double walk[3];
} clipmap_bench;

static double sample_build(void *user) {
    clipmap_bench *b = user;
    double camera[3] = { 100000.0 * ++b->run, 50.0, -3000.0 };
    uint64_t start = core_time_ns();
    terrain_clipmap_update(b->clipmap, camera);
    return core_ns_to_ms(core_time_ns() - start);
}

#define WALK_STEPS 128

static double sample_walk(void *user) {
    clipmap_bench *b = user;
    uint64_t start = core_time_ns();
    for (int step = 0; step < WALK_STEPS; step++) {
        b->walk[0] += 4.0 * 0.8;
        b->walk[2] -= 4.0 * 0.6;
        terrain_clipmap_update(b->clipmap, b->walk);
    }
    return core_ns_to_ms(core_time_ns() - start) / WALK_STEPS;
}

void bench_group_terrain_clipmap(bench_context *ctx) {
    if (!bench_wants(ctx, "terrain.clipmap")) return;
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = bench_threads(ctx) });
    clipmap_bench b = { .clipmap = terrain_clipmap_create(&(terrain_clipmap_desc){
                            .generation = terrain_generation_defaults(42), .jobs = jobs }),
                        .walk = { 200.0, 60.0, 100.0 } };
    bench_run(ctx, "terrain.clipmap.build", "ms", 9, sample_build, &b);
    terrain_clipmap_update(b.clipmap, b.walk);
    bench_run(ctx, "terrain.clipmap.update_step", "ms", 9, sample_walk, &b);

    if (bench_wants(ctx, "terrain.clipmap.triangles")) {
        double camera[3] = { 200.0, 0.0, 100.0 };
        terrain_clipmap_update(b.clipmap, camera);
        camera[1] = terrain_clipmap_height(b.clipmap, camera[0], camera[2]) + 60.0;
        double triangles[8];
        for (int d = 0; d < 8; d++) {
            terrain_view view = { .camera = { camera[0], camera[1], camera[2] }, .yaw = (float)d * 0.785f,
                                  .aspect = 16.0f / 9.0f };
            terrain_frustum frustum = terrain_frustum_from_view(&view);
            terrain_clipmap_cull(b.clipmap, &frustum);
            triangles[d] = (double)terrain_clipmap_stats(b.clipmap).triangles_visible;
        }
        bench_record(ctx, "terrain.clipmap.triangles", "count", triangles, 8);
    }
    terrain_clipmap_destroy(b.clipmap);
    job_system_destroy(jobs);
}
