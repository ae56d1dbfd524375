/* Editing a running world (terrain.h, "editing in the ECS"; terrain_ecs_edit.c): the queue, the
 * stabilize phase that applies it, stabilization across chunks over several frames, refusals.
 * No mesh chunk is spawned or streamed, so nothing is uploaded and no GL context is needed; the
 * tests that look at what an edit draws are in tests/render (render_stream, render_grass,
 * render_rocks, render_world). The world is flat bedrock up to y = 0, made by hand, so every
 * quantum of sand in it came from the edits: a deposit of V m³ is round(32·V) quanta (000 §4.3,
 * terrain.h "brushes"), and stabilization moves material without making or losing any (§3.4). */
#include "../engine/test.h"
#include "terrain/terrain.h"
#include "terrain_quanta_test.h"

#include "core/core.h"
#include "ecs/ecs.h"
#include "jobs/jobs.h"

#include <math.h>

#define DT (1.0f / 60.0f)

static void flat_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    (void)user, (void)x, (void)z;
    terrain_stacks_builder_push(builder, TERRAIN_BEDROCK, -TERRAIN_FLOOR_Y);
}

static terrain_stacks *flat_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, flat_column, user);
}

typedef struct running {
    job_system *jobs;
    ecs_world *ecs;
    terrain_world *world;
    terrain_ecs *te;
} running;

static running running_open_on(int threads) {
    running r = { .jobs = job_system_create(&(job_system_desc){ .threads = threads }) };
    r.ecs = ecs_world_create(&(ecs_world_desc){ .jobs = r.jobs });
    r.world = terrain_world_create(&(terrain_world_desc){ .generate = flat_chunk });
    r.te = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = r.ecs, .terrain = r.world });
    cr_assert(r.te);
    return r;
}

static running running_open(void) { return running_open_on(2); }

static void running_close(running *r) {
    terrain_ecs_destroy(r->te);
    ecs_world_destroy(r->ecs);
    terrain_world_destroy(r->world);
    job_system_destroy(r->jobs);
}

/* Two strokes queued: nothing changes until the next frame's stabilize phase, which applies
 * both; 10 m³ each is 320 quanta each, all of it in the world (a pile of 10 m³ in the middle of
 * chunk (0, 0) cannot slide further than its neighbours). */
Test(terrain_ecs_edit, edits_wait_in_the_queue_and_the_next_frame_applies_them) {
    running r = running_open();
    const terrain_edit stroke = { .tool = TERRAIN_EDIT_DEPOSIT,
                                  .deposit = { .x = 16.5, .z = 16.5, .radius = 2, .volume = 10 } };
    cr_assert(terrain_ecs_edit(r.te, &stroke));
    cr_assert(terrain_ecs_edit(r.te, &stroke));
    terrain_ecs_edit_stats_info st = terrain_ecs_edit_stats(r.te);
    cr_expect_eq(st.queued, 2);
    cr_expect_eq(st.edits_applied, 0);
    cr_expect_eq(world_quanta(r.world, -1, 1, -1, 1, TERRAIN_SAND), 0, "queued, not applied");
    ecs_progress(r.ecs, DT);
    terrain_world_trim(r.world);
    st = terrain_ecs_edit_stats(r.te);
    cr_expect_eq(st.queued, 0);
    cr_expect_eq(st.edits_applied, 2);
    cr_expect_eq(st.edits_refused, 0);
    cr_expect_eq(world_quanta(r.world, -1, 1, -1, 1, TERRAIN_SAND), 2 * 320, "applied in the frame after they were queued");
    running_close(&r);
}

/* A steep pile on the corner of four chunks, at most 8 iterations a frame: it slides into all
 * four over several frames until it is stable, and not a quantum is lost or made. A 300 m³ cone
 * of sand at 33° has a radius of (3·300 / (π·tan 33°))^(1/3) ≈ 7.6 m, so each quarter of it
 * (≈ 2400 quanta) lies in one of the four chunks, far more than the 1000 asked for below. */
Test(terrain_ecs_edit, a_pile_on_a_chunk_corner_spreads_into_four_chunks_and_keeps_its_mass) {
    running r = running_open();
    terrain_ecs_set_editing(r.te, &(terrain_editing_desc){ .stabilize = { .max_iterations = 8 } });
    cr_assert(terrain_ecs_edit(r.te, &(terrain_edit){ .tool = TERRAIN_EDIT_DEPOSIT,
                                                      .deposit = { .x = 0.5, .z = 0.5, .radius = 2, .volume = 300 } }));
    int frames = 0;
    for (; frames < 3000; frames++) {
        ecs_progress(r.ecs, DT);
        terrain_world_trim(r.world);
        if (terrain_ecs_edit_stats(r.te).stabilizing_chunks == 0 && frames > 0) break;
    }
    cr_assert_lt(frames, 3000, "never stable");
    terrain_ecs_edit_stats_info st = terrain_ecs_edit_stats(r.te);
    cr_expect_eq(st.edits_applied, 1);
    cr_expect_gt(st.iterations, 8, "took several frames of 8 iterations");
    cr_expect_geq(st.chunks_committed, 4);
    cr_expect_eq(world_quanta(r.world, -3, 2, -3, 2, TERRAIN_SAND), 300 * 32, "sand in the world: exactly the deposit");
    for (int c = 0; c < 4; c++) {
        int64_t cx = c & 1 ? 0 : -1, cz = c & 2 ? 0 : -1;
        cr_expect_gt(chunk_quanta(terrain_world_stacks(r.world, (terrain_chunk_coord){ cx, cz }), TERRAIN_SAND), 1000, "chunk (%lld, %lld)", (long long)cx, (long long)cz);
    }
    running_close(&r);
}

/* Only brushes are queued: no edit, a tool that is not a brush, a sweep without points are
 * refused (counted, nothing queued, the world untouched). */
Test(terrain_ecs_edit, what_is_not_a_brush_is_refused_and_nothing_is_queued) {
    running r = running_open();
    core_log_level level = core_log_get_level();
    core_log_set_level(CORE_LOG_OFF);   /* each refusal logs a message */
    cr_expect_not(terrain_ecs_edit(r.te, NULL));
    cr_expect_not(terrain_ecs_edit(r.te, &(terrain_edit){ .tool = TERRAIN_EDIT_SET }));
    cr_expect_not(terrain_ecs_edit(r.te, &(terrain_edit){ .tool = TERRAIN_EDIT_STABILIZE }));
    cr_expect_not(terrain_ecs_edit(r.te, &(terrain_edit){ .tool = TERRAIN_EDIT_SWEEP, .sweep = { .radius = 2 } }));
    core_log_set_level(level);
    terrain_ecs_edit_stats_info st = terrain_ecs_edit_stats(r.te);
    cr_expect_eq(st.edits_refused, 4);
    cr_expect_eq(st.queued, 0);
    ecs_progress(r.ecs, DT);
    cr_expect_eq(terrain_ecs_edit_stats(r.te).edits_applied, 0);
    cr_expect_eq(world_quanta(r.world, -1, 1, -1, 1, TERRAIN_SAND), 0);
    running_close(&r);
}

/* Exact replays (issue 16): with the stabilization budgeted in iterations, where a slide is after
 * each frame is a function of the edits and the frame count alone, not of the machine's speed or
 * the thread count. The same strokes on 1 and 3 threads give the same bytes in all four chunks
 * after every frame, including a second stroke queued while the first still slides. */
static uint64_t corner_hash(terrain_world *w) {
    uint64_t h = 0;
    for (int c = 0; c < 4; c++)
        h = core_hash_combine(h, terrain_stacks_hash(terrain_world_stacks(w, (terrain_chunk_coord){ c & 1 ? 0 : -1,
                                                                                                   c & 2 ? 0 : -1 })));
    return h;
}

Test(terrain_ecs_edit, budgeted_in_iterations_a_slide_is_the_same_bytes_every_frame_on_any_thread_count) {
    enum { FRAMES = 12 };
    uint64_t hashes[2][FRAMES];
    int sliding[2][FRAMES];
    for (int run = 0; run < 2; run++) {
        running r = running_open_on(run ? 3 : 1);
        terrain_ecs_set_editing(r.te, &(terrain_editing_desc){ .stabilize = { .max_iterations = 2 } });
        cr_assert(terrain_ecs_edit(r.te, &(terrain_edit){ .tool = TERRAIN_EDIT_DEPOSIT,
                                                          .deposit = { .x = 0.5, .z = 0.5, .radius = 2, .volume = 200 } }));
        for (int f = 0; f < FRAMES; f++) {
            if (f == 4)
                cr_assert(terrain_ecs_edit(r.te, &(terrain_edit){ .tool = TERRAIN_EDIT_DEPOSIT,
                                                                  .deposit = { .x = -3, .z = 2, .radius = 1.5f,
                                                                               .volume = 60 } }));
            ecs_progress(r.ecs, DT);
            terrain_world_trim(r.world);
            hashes[run][f] = corner_hash(r.world);
            sliding[run][f] = terrain_ecs_edit_stats(r.te).stabilizing_chunks;
        }
        cr_expect_eq(world_quanta(r.world, -3, 2, -3, 2, TERRAIN_SAND), (200 + 60) * 32, "mass kept");
        running_close(&r);
    }
    cr_expect_gt(sliding[0][FRAMES - 1], 0, "still sliding after %d frames of 2 iterations: the budget bound", FRAMES);
    for (int f = 0; f < FRAMES; f++) {
        cr_expect_eq(hashes[0][f], hashes[1][f], "frame %d: 1 thread and 3 threads differ", f);
        cr_expect_eq(sliding[0][f], sliding[1][f], "frame %d", f);
        if (f) cr_expect_neq(hashes[0][f], hashes[0][f - 1], "frame %d moved sand", f);
    }
}

/* A profiled sweep queued through the ECS carves what the same sweep applied at once carves: the
 * queue keeps its own copy of the profile (the caller's array is overwritten before the frame),
 * and the region it loads holds the profile's reach (a scale of 2.5 here: up to 6.25 m, with
 * the cubic's overshoot, from an axis 4.5 m from a chunk border; the round sweep's reach, 2 m
 * and a margin of 2, would load chunk (0, 0) alone, and the sweep would be refused). */
Test(terrain_ecs_edit, a_profiled_sweep_is_copied_into_the_queue_and_reaches_as_far_as_its_profile) {
    double line[2][3] = { { 4, -6, 4.5 }, { 28, -6, 4.5 } };
    float profile[4] = { 2.5f, 1.0f, 1.0f, 1.0f };
    const terrain_edit sweep = { .tool = TERRAIN_EDIT_SWEEP,
                                 .sweep = { .points = (const double (*)[3])line, .point_count = 2, .radius = 2,
                                            .profile = profile, .profile_count = 4 } };
    running direct = running_open();
    cr_assert_geq(terrain_world_edit(direct.world, &sweep, NULL, 0), 1);
    running queued = running_open();
    cr_assert(terrain_ecs_edit(queued.te, &sweep));
    for (int j = 0; j < 4; j++) profile[j] = 0.1f;          /* the caller's array, reused */
    ecs_progress(queued.ecs, DT);
    cr_expect_eq(terrain_ecs_edit_stats(queued.te).edits_applied, 1);
    for (int c = -1; c <= 0; c++) {
        terrain_chunk_coord coord = { 0, c };
        cr_expect_eq(terrain_stacks_hash(terrain_world_stacks(queued.world, coord)),
                     terrain_stacks_hash(terrain_world_stacks(direct.world, coord)), "chunk (0, %d)", c);
    }
    cr_expect_lt(chunk_quanta(terrain_world_stacks(direct.world, (terrain_chunk_coord){ 0, 0 }), TERRAIN_BEDROCK),
                 32 * 32 * (int64_t)(-TERRAIN_FLOOR_Y * 32), "the sweep carved");
    running_close(&direct);
    running_close(&queued);
}

/* ---- what an amplify hook adds reaches past the columns it reads (amplify_reach) ------------- */

/* Ground at y = 8 everywhere; the hook adds a ball of radius 3 at (40, 8, 16), in mesh chunk
 * (1, 0, 0), while column (12, 16) of chunk (0, 0) is flat: its stacks decide the ball, 20 m
 * from chunk (1, 0, 0)'s box, farther than the chunk's own samples, kernel and occlusion rays
 * reach (11 m). So only amplify_reach can tell the ECS that an edit there changes that chunk. */
#define BALL_X 40.0
#define BALL_Y 8.0
#define BALL_Z 16.0
#define BALL_RADIUS 3.0

static void ground8_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    (void)x, (void)z;
    const float *top = user;
    terrain_stacks_builder_push(builder, TERRAIN_BEDROCK, *top - TERRAIN_FLOOR_Y);
}

static terrain_stacks *ground8_chunk(void *user, terrain_chunk_coord coord) {
    (void)user;
    float top = 8.0f;
    return terrain_stacks_from_columns(coord, ground8_column, &top);
}

static void ball_while_flat(void *user, terrain_world *world, terrain_field *field) {
    (void)user;
    const terrain_stacks *deciding = terrain_world_stacks(world, (terrain_chunk_coord){ 0, 0 });
    if (terrain_stacks_top(deciding, 12, 16) > 8.5f) return;
    for (int k = 0; k < field->nz; k++)
        for (int j = 0; j < field->ny; j++)
            for (int i = 0; i < field->nx; i++) {
                double dx = field->origin[0] + i * (double)field->spacing - BALL_X;
                double dy = field->origin[1] + j * (double)field->spacing - BALL_Y;
                double dz = field->origin[2] + k * (double)field->spacing - BALL_Z;
                float t = (float)(BALL_RADIUS - sqrt(dx * dx + dy * dy + dz * dz));
                t = t > 1.0f ? 1.0f : t < -1.0f ? -1.0f : t;
                float *v = &field->values[((size_t)k * field->ny + j) * field->nx + i];
                *v = t > *v ? t : *v;
            }
}

/* The top of mesh chunk (1, 0, 0) as last uploaded, after a few frames. */
static float ball_chunk_top(running *r, ecs_query *query, uint64_t *serial) {
    for (int f = 0; f < 4; f++) ecs_progress(r->ecs, DT);
    ecs_iter it = ecs_query_iter(r->ecs, query);
    float top = -1e9f;
    while (ecs_query_next(&it)) {
        TerrainMeshChunk *chunks = ecs_field(&it, 0);
        for (int i = 0; i < it.count; i++)
            if (chunks[i].x == 1 && chunks[i].y == 0 && chunks[i].z == 0)
                top = chunks[i].gpu.bounds_max[1], *serial = chunks[i].gpu.serial;
    }
    return top;
}

static void one_column_raised(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    (void)user;
    float top = x == 12 && z == 16 ? 13.0f : 8.0f;
    ground8_column(&top, x, z, builder);
}

/* Raises column (12, 16) of chunk (0, 0) to 13 m, a commit as any edit makes; returns the ball
 * chunk's top after it (and before in *before). */
static float ball_after_raising_its_column(float reach_x, float *before, bool *remeshed) {
    running r = { .jobs = job_system_create(&(job_system_desc){ .threads = 2 }) };
    r.ecs = ecs_world_create(&(ecs_world_desc){ .jobs = r.jobs });
    r.world = terrain_world_create(&(terrain_world_desc){ .generate = ground8_chunk, .amplify = ball_while_flat,
                                                          .amplify_reach = { reach_x, 0, 0 } });
    r.te = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = r.ecs, .terrain = r.world });
    cr_assert(r.te);
    ecs_query *query = ecs_query_create(r.ecs, &(ecs_query_desc){ .with = { ecs_component_lookup(r.ecs, "TerrainMeshChunk") } });
    terrain_ecs_spawn_area(r.te, 0, 0, 1, 0, 0);   /* column chunks −1 … 1, mesh layer 0 (y 0 … 32) */
    core_log_level level = core_log_get_level();
    core_log_set_level(CORE_LOG_OFF);   /* no GL context: the uploads say so, and keep the bounds */
    uint64_t serial_before = 0, serial_after = 0;
    *before = ball_chunk_top(&r, query, &serial_before);

    terrain_world_commit(r.world, (terrain_chunk_coord){ 0, 0 },
                         terrain_stacks_from_columns((terrain_chunk_coord){ 0, 0 }, one_column_raised, NULL), TERRAIN_EDIT_SET);
    float after = ball_chunk_top(&r, query, &serial_after);
    *remeshed = serial_after != serial_before;
    core_log_set_level(level);
    ecs_query_destroy(r.ecs, query);
    running_close(&r);
    return after;
}

Test(terrain_ecs_edit, an_edit_meshes_again_the_chunks_within_the_amplify_hook_s_reach) {
    /* the ball's farthest point is |12 − 43| = 31 m from the column along x */
    float before, after;
    bool remeshed;
    after = ball_after_raising_its_column(32.0f, &before, &remeshed);
    cr_expect_geq(before, (float)(BALL_Y + BALL_RADIUS - 1.0), "the ball is drawn at first: top %g", (double)before);
    cr_expect(remeshed, "the chunk 20 m from the edit is meshed again");
    /* flat ground's top is 8 m; the ball's is 11 m (bounds may carry a metre of margin) */
    cr_expect_lt(after, (float)(BALL_Y + BALL_RADIUS - 1.0), "and the ball is gone from it: top %g", (double)after);
    /* without the reach the chunk keeps drawing a ball that is no longer in the field */
    after = ball_after_raising_its_column(0.0f, &before, &remeshed);
    cr_expect_geq(before, (float)(BALL_Y + BALL_RADIUS - 1.0));
    cr_expect_not(remeshed, "without amplify_reach nothing tells the chunk");
    cr_expect_geq(after, (float)(BALL_Y + BALL_RADIUS - 1.0));
}

/* Frames until every wanted chunk is drawn again (a minute at most, for a loaded machine); the
 * ball chunk's top then. */
static float streamed_ball_top(running *r, ecs_query *query) {
    const double eye[1][3] = { { 16, 10, 16 } };
    uint64_t give_up = core_time_ns() + 60ull * 1000000000ull, serial = 0;
    for (int f = 0; f < 2000 || core_time_ns() < give_up; f++) {
        terrain_ecs_set_viewers(r->te, eye, 1);
        ecs_progress(r->ecs, DT);
        terrain_world_trim(r->world);
        terrain_ecs_stream_stats_info st = terrain_ecs_stream_stats(r->te);
        if (f > 2 && st.mesh_chunks_wanted > 0 && st.mesh_chunks_ready == st.mesh_chunks_wanted) break;
    }
    return ball_chunk_top(r, query, &serial);
}

/* Streamed, the chunks only the reach meets are meshed again in the background, and still come
 * back without the ball. */
Test(terrain_ecs_edit, streamed_chunks_within_the_amplify_hook_s_reach_are_meshed_again) {
    running r = { .jobs = job_system_create(&(job_system_desc){ .threads = 2 }) };
    r.ecs = ecs_world_create(&(ecs_world_desc){ .jobs = r.jobs });
    r.world = terrain_world_create(&(terrain_world_desc){ .generate = ground8_chunk, .amplify = ball_while_flat,
                                                          .amplify_reach = { 32, 0, 0 } });
    r.te = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = r.ecs, .terrain = r.world });
    cr_assert(r.te);
    ecs_query *query = ecs_query_create(r.ecs, &(ecs_query_desc){ .with = { ecs_component_lookup(r.ecs, "TerrainMeshChunk") } });
    terrain_ecs_stream(r.te, &(terrain_stream_desc){ .half_width = 2, .levels = 1, .y_min = 0, .y_max = 20 });
    core_log_level level = core_log_get_level();
    core_log_set_level(CORE_LOG_OFF);   /* no GL context: the uploads say so, and keep the bounds */
    float before = streamed_ball_top(&r, query);
    terrain_world_commit(r.world, (terrain_chunk_coord){ 0, 0 },
                         terrain_stacks_from_columns((terrain_chunk_coord){ 0, 0 }, one_column_raised, NULL), TERRAIN_EDIT_SET);
    float after = streamed_ball_top(&r, query);
    core_log_set_level(level);
    cr_expect_geq(before, (float)(BALL_Y + BALL_RADIUS - 1.0), "the ball is drawn at first: top %g", (double)before);
    cr_expect_lt(after, (float)(BALL_Y + BALL_RADIUS - 1.0), "and is gone after the edit: top %g", (double)after);
    ecs_query_destroy(r.ecs, query);
    running_close(&r);
}
