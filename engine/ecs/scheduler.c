/* scheduler.c — phases, systems, and running a frame on the job system.
 *
 * Each phase becomes a small graph of jobs. A system's jobs start after the jobs of every
 * earlier system of the phase it conflicts with (one writes what the other reads or writes);
 * systems that do not conflict get no edge between them and run at the same time. A parallel
 * system has one job per batch of its query. Batches are cut before the phase starts: nothing
 * structural changes while a phase runs, so tables keep their rows until the phase ends.
 *
 * Every invocation (a system call, or one batch of a parallel system) records into a command
 * buffer of its own, and the buffers are applied after the phase in registration order, then
 * batch order. Batch sizes never depend on the thread count, so neither does anything else.
 */
#include "ecs_internal.h"

#include <stdlib.h>
#include <string.h>

#include "trace/trace.h"

struct ecs_system_info {
    char *name;
    const char *trace_name;          /* trace_intern'ed: outlives the world */
    ecs_query *query;                /* NULL: the system has no query */
    ecs_component reads[ECS_MAX_ACCESS + 2 * ECS_MAX_TERMS];
    ecs_component writes[ECS_MAX_ACCESS];
    int read_count, write_count;
    ecs_system_fn fn;
    void *user;
    bool main_thread, parallel;
    bool exclusive;                  /* declared nothing: runs alone in its phase (ecs.h, ACCESS) */
    bool disabled;                   /* ecs_system_enable(…, false): planned with no invocation */
    int batch_size;
    uint32_t *conflicts;             /* positions in the phase of earlier conflicting systems */
    uint32_t conflict_count, conflict_capacity;
    ecs_commands **buffers;          /* one per invocation, kept from frame to frame */
    uint32_t buffer_count, buffer_capacity;

    /* This phase run only (the memory comes from world->frame). */
    struct ecs_invocation *invocations;
    job_handle *handles;
    uint32_t invocation_count;
};

/* One call of a system's function: the whole query, or one batch of it. */
typedef struct ecs_invocation {
    ecs_world *world;
    ecs_system_info *system;
    ecs_commands *commands;
    bool is_batch;
    ecs_batch batch;
    float dt;
    uint64_t work_ns;                /* how long it ran, when run as a job */
} ecs_invocation;

/* ---- phases ----------------------------------------------------------------------------- */

static int phase_find(const ecs_world *world, const char *name) {
    for (uint32_t i = 0; i < world->phase_count; i++)
        if (strcmp(world->phases[i].name, name) == 0) return (int)i;
    return -1;
}

static void phase_insert(ecs_world *world, uint32_t at, const char *name) {
    world->phases = ecs_grow(world->phases, &world->phase_capacity, world->phase_count + 1,
                             sizeof *world->phases);
    memmove(&world->phases[at + 1], &world->phases[at],
            (world->phase_count - at) * sizeof *world->phases);
    world->phases[at] = (ecs_phase){ .name = core_strdup(name), .trace_name = trace_intern(name),
                                     .work_ns = UINT64_MAX };
    world->phase_count++;
}

void ecs_pipeline_init(ecs_world *world) {
    static const char *const pipeline[] = { "input", "game",  "stream", "generate", "stabilize",
                                            "mesh",  "lod",   "cull",   "draw",     "background" };
    for (uint32_t i = 0; i < CORE_COUNTOF(pipeline); i++) phase_insert(world, i, pipeline[i]);
}

bool ecs_phase_add(ecs_world *world, const char *name, const char *after) {
    ECS_ASSERT_STRUCTURAL(world);
    int before = phase_find(world, after);
    if (before < 0) {
        core_log_error("ecs", "phase '%s': no phase '%s' to add it after", name, after);
        return false;
    }
    if (phase_find(world, name) >= 0) {
        core_log_error("ecs", "phase '%s' exists already", name);
        return false;
    }
    phase_insert(world, (uint32_t)before + 1, name);
    return true;
}

/* ---- systems ---------------------------------------------------------------------------- */

static bool contains(const ecs_component *list, int count, ecs_component component) {
    for (int i = 0; i < count; i++)
        if (list[i] == component) return true;
    return false;
}

static bool writes_what_other_touches(const ecs_system_info *a, const ecs_system_info *b) {
    for (int i = 0; i < a->write_count; i++)
        if (contains(b->reads, b->read_count, a->writes[i]) ||
            contains(b->writes, b->write_count, a->writes[i]))
            return true;
    return false;
}

static bool systems_conflict(const ecs_system_info *a, const ecs_system_info *b) {
    return a->exclusive || b->exclusive || writes_what_other_touches(a, b) ||
           writes_what_other_touches(b, a);
}

static void add_access(ecs_component *list, int *count, const ecs_component *from, int max) {
    for (int i = 0; i < max && from[i]; i++)
        if (!contains(list, *count, from[i])) list[(*count)++] = from[i];
}

static bool query_desc_is_empty(const ecs_query_desc *desc) {
    return !desc->with[0] && !desc->without[0] && !desc->optional[0];
}

ecs_system ecs_system_add(ecs_world *world, const ecs_system_desc *desc) {
    ECS_ASSERT_STRUCTURAL(world);
    assert(desc && desc->fn && desc->phase);
    int phase_index = phase_find(world, desc->phase);
    if (phase_index < 0) {
        core_log_error("ecs", "system '%s': no phase '%s'", desc->name ? desc->name : "?",
                   desc->phase);
        return 0;
    }
    ecs_phase *phase = &world->phases[phase_index];
    const char *name = desc->name ? desc->name : "system";

    ecs_system_info *system = core_calloc(1, sizeof *system);
    system->name = core_strdup(name);
    system->trace_name = trace_intern(name);
    system->fn = desc->fn;
    system->user = desc->user;
    system->main_thread = desc->main_thread;
    system->parallel = desc->parallel;
    system->batch_size = desc->batch_size > 0 ? desc->batch_size : ECS_DEFAULT_BATCH_SIZE;
    if (!query_desc_is_empty(&desc->query)) system->query = ecs_query_create(world, &desc->query);

    /* What the system touches: its writes, and as reads everything else it names. */
    add_access(system->writes, &system->write_count, desc->writes, ECS_MAX_ACCESS);
    add_access(system->reads, &system->read_count, desc->reads, ECS_MAX_ACCESS);
    add_access(system->reads, &system->read_count, desc->query.with, ECS_MAX_TERMS);
    add_access(system->reads, &system->read_count, desc->query.optional, ECS_MAX_TERMS);
    system->exclusive = !system->query && !system->read_count && !system->write_count;

    for (uint32_t i = 0; i < phase->system_count; i++) {
        if (!systems_conflict(system, phase->systems[i])) continue;
        system->conflicts = ecs_grow(system->conflicts, &system->conflict_capacity,
                                     system->conflict_count + 1, sizeof *system->conflicts);
        system->conflicts[system->conflict_count++] = i;
    }

    phase->systems = ecs_grow(phase->systems, &phase->system_capacity, phase->system_count + 1,
                              sizeof *phase->systems);
    phase->systems[phase->system_count++] = system;
    world->systems = ecs_grow(world->systems, &world->system_capacity, world->system_count + 1,
                              sizeof *world->systems);
    world->systems[world->system_count++] = system;
    return world->system_count;
}

void ecs_system_enable(ecs_world *world, ecs_system system, bool enabled) {
    ECS_ASSERT_STRUCTURAL(world);
    assert(system >= 1 && system <= world->system_count && "not a system of this world");
    world->systems[system - 1]->disabled = !enabled;
}

static void system_free(ecs_system_info *system) {
    for (uint32_t i = 0; i < system->buffer_count; i++) ecs_commands_destroy(system->buffers[i]);
    core_free(system->buffers, system->buffer_capacity * sizeof *system->buffers);
    core_free(system->conflicts, system->conflict_capacity * sizeof *system->conflicts);
    core_free(system->name, strlen(system->name) + 1);
    core_free(system, sizeof *system);
}

void ecs_scheduler_free(ecs_world *world) {
    for (uint32_t i = 0; i < world->system_count; i++) system_free(world->systems[i]);
    core_free(world->systems, world->system_capacity * sizeof *world->systems);
    for (uint32_t i = 0; i < world->phase_count; i++) {
        ecs_phase *phase = &world->phases[i];
        core_free(phase->systems, phase->system_capacity * sizeof *phase->systems);
        core_free(phase->name, strlen(phase->name) + 1);
    }
    core_free(world->phases, world->phase_capacity * sizeof *world->phases);
}

/* ---- access checks (debug builds) --------------------------------------------------------- */

/* The system whose function runs on this thread, and its world. A system that waits on jobs may
 * run another system's invocation on this thread meanwhile: invocation_run saves and restores. */
static _Thread_local const ecs_system_info *running_system;
static _Thread_local const ecs_world *running_world;

#ifndef NDEBUG
static bool access_declared(const ecs_system_info *system, ecs_component component, bool write) {
    if (contains(system->writes, system->write_count, component)) return true;
    return !write && contains(system->reads, system->read_count, component);
}

static void access_refuse(const ecs_world *world, const ecs_system_info *system,
                          ecs_component component, bool write, const char *call) {
    const char *name = component > 0 && component < world->component_count
                           ? world->components[component].name : "?";
    core_log_error("ecs", "system '%s' calls %s on %s '%s' without declaring it in %s", system->name,
               call, ecs_is_resource(world, component) ? "resource" : "component", name,
               write ? "its writes" : "its reads or writes");
    abort();
}

void ecs_access_check(const ecs_world *world, ecs_component component, bool write, const char *call) {
    const ecs_system_info *system = running_system;
    if (!system || running_world != world || system->exclusive) return;
    if (!access_declared(system, component, write)) access_refuse(world, system, component, write, call);
}

void ecs_access_check_query(const ecs_world *world, const ecs_query *query) {
    const ecs_system_info *system = running_system;
    if (!system || running_world != world || system->exclusive || query == system->query) return;
    for (int i = 0; i < query->with_count; i++)
        if (!access_declared(system, query->with[i], false))
            access_refuse(world, system, query->with[i], false, "ecs_query_iter");
    for (int i = 0; i < query->optional_count; i++)
        if (!access_declared(system, query->optional[i], false))
            access_refuse(world, system, query->optional[i], false, "ecs_query_iter");
}
#endif

/* ---- running a frame -------------------------------------------------------------------- */

static void invocation_run(void *user) {
    ecs_invocation *invocation = user;
    const ecs_system_info *system = invocation->system;
    const ecs_system_info *outer_system = running_system;
    const ecs_world *outer_world = running_world;
    running_system = system;
    running_world = invocation->world;
    ecs_iter it = invocation->is_batch
                      ? ecs_batch_iter(invocation->world, system->query, invocation->batch)
                      : ecs_query_iter(invocation->world, system->query);
    it.dt = invocation->dt;
    it.commands = invocation->commands;
    it.user = system->user;
    system->fn(&it);
    running_system = outer_system;
    running_world = outer_world;
}

/* A job's body: the invocation, timed, so the phase knows what its systems cost. */
static void invocation_job(void *user) {
    ecs_invocation *invocation = user;
    uint64_t start = core_time_ns();
    invocation_run(invocation);
    invocation->work_ns = core_time_ns() - start;
}

static ecs_commands *system_buffer(ecs_world *world, ecs_system_info *system, uint32_t index) {
    while (system->buffer_count <= index) {
        system->buffers = ecs_grow(system->buffers, &system->buffer_capacity,
                                   system->buffer_count + 1, sizeof *system->buffers);
        system->buffers[system->buffer_count++] = ecs_commands_create(world);
    }
    return system->buffers[index];
}

/* Decides the system's invocations for this phase run: one, or one per batch. */
static void system_plan(ecs_world *world, ecs_system_info *system, float dt) {
    uint32_t count = system->disabled ? 0 : 1;
    ecs_batch *batches = NULL;
    if (count && system->parallel && system->query) {
        count = (uint32_t)ecs_query_batches(world, system->query, system->batch_size, NULL, 0);
        batches = core_arena_alloc(&world->frame, (count + 1) * sizeof *batches,
                                   alignof(ecs_batch));
        ecs_query_batches(world, system->query, system->batch_size, batches, (int)count);
    }
    system->invocation_count = count;
    system->invocations = core_arena_alloc(&world->frame, (count + 1) * sizeof(ecs_invocation),
                                           alignof(ecs_invocation));
    system->handles = core_arena_alloc(&world->frame, (count + 1) * sizeof(job_handle),
                                       alignof(job_handle));
    for (uint32_t i = 0; i < count; i++) {
        system->invocations[i] = (ecs_invocation){
            .world = world, .system = system, .commands = system_buffer(world, system, i),
            .is_batch = batches != NULL, .batch = batches ? batches[i] : (ecs_batch){ 0 },
            .dt = dt };
        system->handles[i] = (job_handle){ 0, 0 };
    }
}

/* The handles of every job of the earlier systems this one conflicts with. */
static int system_dependencies(ecs_world *world, const ecs_phase *phase,
                               const ecs_system_info *system, job_handle **handles) {
    *handles = NULL;
    if (!system->conflict_count) return 0;
    uint32_t total = 0;
    for (uint32_t i = 0; i < system->conflict_count; i++)
        total += phase->systems[system->conflicts[i]]->invocation_count;
    *handles = core_arena_alloc(&world->frame, (total + 1) * sizeof **handles, alignof(job_handle));
    uint32_t filled = 0;
    for (uint32_t i = 0; i < system->conflict_count; i++) {
        const ecs_system_info *earlier = phase->systems[system->conflicts[i]];
        for (uint32_t k = 0; k < earlier->invocation_count; k++)
            (*handles)[filled++] = earlier->handles[k];
    }
    return (int)filled;
}

/* The invocation of the phase submitted last (NULL when the phase has none). */
static ecs_invocation *phase_last_invocation(const ecs_phase *phase) {
    for (uint32_t s = phase->system_count; s-- > 0;) {
        ecs_system_info *system = phase->systems[s];
        if (system->invocation_count) return &system->invocations[system->invocation_count - 1];
    }
    return NULL;
}

static void phase_run_on_jobs(ecs_world *world, ecs_phase *phase) {
    /* The last invocation runs here instead of going through a queue when it waits for
     * nothing: no later system can depend on it, this thread would only wait meanwhile, and a
     * phase of one invocation then never wakes a worker. */
    ecs_invocation *last = phase_last_invocation(phase);
    ecs_invocation *inline_run = NULL;
    for (uint32_t s = 0; s < phase->system_count; s++) {
        ecs_system_info *system = phase->systems[s];
        job_handle *after;
        int after_count = system_dependencies(world, phase, system, &after);
        for (uint32_t i = 0; i < system->invocation_count; i++) {
            if (&system->invocations[i] == last && after_count == 0) {
                inline_run = last;
                system->handles[i] = (job_handle){ 0, 0 };   /* reads as done */
                continue;
            }
            system->handles[i] = job_submit(world->jobs, &(job_desc){
                .fn = invocation_job, .user = &system->invocations[i],
                .name = system->trace_name, /* the job system opens the zone */
                .after = after, .after_count = after_count, .main_thread = system->main_thread });
        }
    }
    if (inline_run) {
        trace_zone_begin(inline_run->system->trace_name);
        invocation_job(inline_run);
        trace_zone_end();
    }
    /* Waiting runs jobs on this thread too, main-thread systems among them. */
    for (uint32_t s = 0; s < phase->system_count; s++) {
        ecs_system_info *system = phase->systems[s];
        for (uint32_t i = 0; i < system->invocation_count; i++)
            job_wait(world->jobs, system->handles[i]);
    }
}

static void phase_run_here(ecs_phase *phase) {
    for (uint32_t s = 0; s < phase->system_count; s++) {
        ecs_system_info *system = phase->systems[s];
        for (uint32_t i = 0; i < system->invocation_count; i++) {
            trace_zone_begin(system->trace_name);
            invocation_run(&system->invocations[i]);
            trace_zone_end();
        }
    }
}

static void phase_apply_commands(ecs_phase *phase) {
    for (uint32_t s = 0; s < phase->system_count; s++) {
        ecs_system_info *system = phase->systems[s];
        for (uint32_t i = 0; i < system->invocation_count; i++)
            ecs_commands_apply(system->invocations[i].commands);
    }
}

/* A phase runs on the calling thread, without the job system, when its systems took less
 * than this in all last frame and none has more than one batch now: waking workers for it
 * would cost more than they could save (ecs.progress.100systems, 100 trivial systems: from
 * about 110 us to 5-8 us a frame on 16 threads). A parallel system with several batches has work to share
 * now, whatever it cost last frame, so its phase goes to the job system. */
enum { ECS_INLINE_PHASE_NS = 20000 };

static bool phase_is_light(const ecs_phase *phase) {
    if (phase->work_ns >= ECS_INLINE_PHASE_NS) return false;
    for (uint32_t s = 0; s < phase->system_count; s++)
        if (phase->systems[s]->invocation_count > 1) return false;
    return true;
}

static uint64_t phase_jobs_work(const ecs_phase *phase) {
    uint64_t total = 0;
    for (uint32_t s = 0; s < phase->system_count; s++) {
        const ecs_system_info *system = phase->systems[s];
        for (uint32_t i = 0; i < system->invocation_count; i++)
            total += system->invocations[i].work_ns;
    }
    return total;
}

static void phase_run(ecs_world *world, ecs_phase *phase, float dt) {
    core_arena_reset(&world->frame);
    for (uint32_t s = 0; s < phase->system_count; s++) system_plan(world, phase->systems[s], dt);
    world->in_phase = true;
    if (world->jobs && !phase_is_light(phase)) {
        phase_run_on_jobs(world, phase);
        phase->work_ns = phase_jobs_work(phase);
    } else {
        uint64_t start = core_time_ns();
        phase_run_here(phase);
        phase->work_ns = core_time_ns() - start;
    }
    world->in_phase = false;
    phase_apply_commands(phase);
}

void ecs_progress(ecs_world *world, float dt) {
    ECS_ASSERT_STRUCTURAL(world);
    assert((!world->jobs || job_thread_index(world->jobs) == 0) &&
           "ecs_progress belongs to the thread that created the job system");
    for (uint32_t i = 0; i < world->phase_count; i++) {
        ecs_phase *phase = &world->phases[i];
        trace_zone_begin(phase->trace_name);
        phase_run(world, phase, dt);
        trace_zone_end();
    }
    ecs_world_frame_end(world);
}
