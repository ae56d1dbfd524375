/* ecs_systems — the engine in one short program: components, systems in phases, parallel
 * and main-thread systems, deferred spawning, work handed out after the draw that spans frames,
 * and a trace of every frame.
 *
 *   ecs_systems [--frames N] [--particles N] [--threads N] [--trace FILE]
 *
 * Particles are born at a fountain, fly under gravity, bounce on the ground and die of old age.
 * tools/play runs it with a trace and prints the trace report.
 */
#include "core/core.h"
#include "ecs/ecs.h"
#include "jobs/jobs.h"
#include "trace/trace.h"

#include <math.h>
#include <stdio.h>

/* Components: plain data. */
typedef struct Position { float x, y, z; } Position;
typedef struct Velocity { float x, y, z; } Velocity;
typedef struct Lifetime { float seconds_left; } Lifetime;

/* A count the census job makes from its own copy of the heights, while the frames go on. */
typedef struct census {
    float *heights;
    size_t count, capacity;
    int above;           /* particles over 1 m when the copy was taken */
    job_handle job;      /* the count's job (the zero handle, none yet, reads as done) */
    bool started;
} census;

typedef struct demo {
    ecs_component position, velocity, lifetime;
    int target_particles;
    uint64_t spawned;
    float highest;       /* written by the draw system, on the main thread */
    census census;
    int censuses, last_above;
} demo;

/* input: keep the fountain full. Spawning is deferred: entities appear at the end of the phase. */
static void spawn(ecs_iter *it) {
    demo *d = it->user;
    int missing = d->target_particles - ecs_entity_count(it->world);
    for (int i = 0; i < missing && i < 2000; i++) {
        /* Random numbers come from a hash of a counter, never from a shared generator. */
        uint64_t h = core_hash_u64(d->spawned++);
        float angle = (float)(h & 0xffff) * (6.2831853f / 65536.0f);
        float speed = 2.0f + (float)((h >> 16) & 0xff) * (3.0f / 255.0f);
        ecs_entity e = ecs_defer_entity_create(it->commands);
        ecs_defer_set(it->commands, e, d->position, &(Position){ 0, 0, 0 });
        ecs_defer_set(it->commands, e, d->velocity, &(Velocity){ cosf(angle) * speed, 8.0f, sinf(angle) * speed });
        ecs_defer_set(it->commands, e, d->lifetime, &(Lifetime){ 1.0f + (float)((h >> 24) & 0xff) / 64.0f });
    }
}

/* game: integrate, in parallel batches over all cores. */
static void fly(ecs_iter *it) {
    while (ecs_query_next(it)) {
        Position *p = ecs_field(it, 0);
        Velocity *v = ecs_field(it, 1);
        for (int i = 0; i < it->count; i++) {
            v[i].y -= 9.81f * it->dt;
            p[i].x += v[i].x * it->dt;
            p[i].y += v[i].y * it->dt;
            p[i].z += v[i].z * it->dt;
        }
    }
}

/* physics (a phase this program adds after game): bounce on the ground, losing energy. */
static void bounce(ecs_iter *it) {
    while (ecs_query_next(it)) {
        Position *p = ecs_field(it, 0);
        Velocity *v = ecs_field(it, 1);
        for (int i = 0; i < it->count; i++) {
            if (p[i].y < 0) {
                p[i].y = -p[i].y;
                v[i].y = -v[i].y * 0.6f;
            }
        }
    }
}

/* physics too, but it touches only Lifetime: it does not conflict with bounce, so the two run
 * at the same time. Deaths are deferred like births. */
static void age(ecs_iter *it) {
    while (ecs_query_next(it)) {
        Lifetime *life = ecs_field(it, 0);
        for (int i = 0; i < it->count; i++) {
            life[i].seconds_left -= it->dt;
            if (life[i].seconds_left <= 0) ecs_defer_entity_destroy(it->commands, it->entities[i]);
        }
    }
}

/* render (in the draw phase): a main-thread system, where OpenGL calls will go. Here it just finds the highest one. */
static void render(ecs_iter *it) {
    demo *d = it->user;
    d->highest = 0;
    while (ecs_query_next(it)) {
        const Position *p = ecs_field(it, 0);
        for (int i = 0; i < it->count; i++) d->highest = fmaxf(d->highest, p[i].y);
    }
}

static void count_above(void *user) {
    census *c = user;
    int above = 0;
    for (size_t i = 0; i < c->count; i++) above += c->heights[i] > 1.0f;
    c->above = above;
}

/* census (in the background phase, the last, after the draw): work that may take longer than a
 * frame goes to the job system as a background job once the frame is drawn, so it runs while
 * the main thread hands the frame over instead of beside the frame's own systems. A finished
 * count is read, and the next one started from a fresh copy (a job never reads components). */
static void census_start(ecs_iter *it) {
    demo *d = it->user;
    job_system *jobs = ecs_world_jobs(it->world);
    census *c = &d->census;
    /* Alone, the main thread is the only one that can run background jobs: up to 1 ms a frame. */
    if (job_thread_count(jobs) == 1) job_help(jobs, 1000000);
    if (!job_is_done(jobs, c->job)) return;   /* the last one is still counting */
    if (c->started) d->last_above = c->above, d->censuses++;
    c->started = true;
    c->count = 0;
    while (ecs_query_next(it)) {
        const Position *p = ecs_field(it, 0);
        c->heights = core_grow(c->heights, &c->capacity, c->count + (size_t)it->count, sizeof *c->heights);
        for (int i = 0; i < it->count; i++) c->heights[c->count++] = p[i].y;
    }
    c->job = job_submit(jobs, &(job_desc){ .fn = count_above, .user = c, .background = true, .name = "census" });
}

int main(int argc, char **argv) {
    core_common_args common = { 0 };
    int frames = 240, particles = 100000;
    core_option options[] = {
        CORE_COMMON_OPTIONS(common),
        { .name = "frames", .kind = CORE_OPTION_INT, .value = &frames, .min = 1, .max = 1000000,
          .metavar = "N", .help = "frames to run (default 240)" },
        { .name = "particles", .kind = CORE_OPTION_INT, .value = &particles, .min = 1, .max = 10000000,
          .metavar = "N", .help = "particles alive at once (default 100000)" },
    };
    core_cli cli = { .program = "ecs_systems", .summary = "A particle fountain on the ECS and job system.",
                     .options = options, .option_count = (int)CORE_COUNTOF(options) };
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    if (common.trace_path && !trace_start(common.trace_path)) return 2;
    trace_thread_name("main");

    job_system *jobs = job_system_create(&(job_system_desc){ .threads = common.threads });
    ecs_world *world = ecs_world_create(&(ecs_world_desc){ .jobs = jobs });
    demo d = { .position = ECS_COMPONENT(world, Position), .velocity = ECS_COMPONENT(world, Velocity),
               .lifetime = ECS_COMPONENT(world, Lifetime), .target_particles = particles };

    ecs_phase_add(world, "physics", "game");
    ecs_system_add(world, &(ecs_system_desc){ .name = "spawn", .phase = "input", .fn = spawn, .user = &d });
    ecs_system_add(world, &(ecs_system_desc){ .name = "fly", .phase = "game", .parallel = true, .fn = fly,
        .query = { .with = { d.position, d.velocity } }, .writes = { d.position, d.velocity } });
    ecs_system_add(world, &(ecs_system_desc){ .name = "bounce", .phase = "physics", .fn = bounce,
        .query = { .with = { d.position, d.velocity } }, .writes = { d.position, d.velocity } });
    ecs_system_add(world, &(ecs_system_desc){ .name = "age", .phase = "physics", .fn = age,
        .query = { .with = { d.lifetime } }, .writes = { d.lifetime } });
    ecs_system_add(world, &(ecs_system_desc){ .name = "render", .phase = "draw", .main_thread = true,
        .fn = render, .user = &d, .query = { .with = { d.position } } });
    ecs_system_add(world, &(ecs_system_desc){ .name = "census", .phase = "background", .main_thread = true,
        .fn = census_start, .user = &d, .query = { .with = { d.position } } });

    uint64_t start = core_time_ns();
    for (int frame = 0; frame < frames; frame++) {
        trace_frame_begin();
        ecs_progress(world, 1.0f / 60.0f);
        trace_counter("entities", ecs_entity_count(world));
        job_system_trace_counters(jobs); /* jobs.run, jobs.stolen, jobs.sleeps, jobs.wakes, jobs.queued */
        trace_frame_end();
    }
    double ms = core_ns_to_ms(core_time_ns() - start);

    printf("ecs_systems: %d frames, %.3f ms per frame on %d threads; %d particles alive, "
           "%llu born, the highest at %.1f m; %d censuses, the last %d over 1 m\n", frames, ms / frames,
           job_thread_count(jobs), ecs_entity_count(world), (unsigned long long)d.spawned, d.highest, d.censuses,
           d.last_above);
    job_wait(jobs, d.census.job);   /* it reads its copy until it is done */
    core_free(d.census.heights, d.census.capacity * sizeof *d.census.heights);
    ecs_world_destroy(world);
    job_system_destroy(jobs);
    trace_stop();
    return 0;
}

/* Expected output:
 * Run: --frames 30 --threads 2 --trace $TMP/run.json
 * ^ecs_systems: 30 frames, [0-9.]+ ms per frame on 2 threads; [1-9][0-9]* particles alive, [1-9][0-9]* born, the highest at [0-9.]+ m; [1-9][0-9]* censuses, the last [0-9]+ over 1 m$
 */
