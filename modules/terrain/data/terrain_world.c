/* terrain_world.c — generated chunks, cached: a hash map from chunk coordinate to stacks under
 * one mutex, an LRU list, retain counts.
 *
 * Chunks are generated outside the lock, so threads generate different chunks in parallel; two
 * threads that race on the same chunk both generate it and the second to finish frees its copy
 * (the bytes are identical: generation is a pure function of (params, coord)).
 *
 * Versions: every commit stamps its chunk with the world's commit count, and an evicted chunk's
 * stamp is kept (`stamps`), so a chunk regenerated from the log keeps the version it had. The
 * same stamps close a race: a thread that generates a chunk outside the lock replays the log as
 * it was when it started; a commit to that chunk followed by its eviction before the thread
 * inserts would let it insert the older copy. A copy whose chunk was stamped after the
 * generation began is therefore thrown away and made again.
 *
 * Eviction never happens inside terrain_world_stacks: a caller may hold pointers to several
 * chunks at once (the field sampler reads up to four) while other threads fetch more. Only
 * terrain_world_trim evicts, at a point the owner chooses (once a frame, when no job reads
 * stacks); see terrain.h.
 */
#include "terrain/data/terrain_data_internal.h"

#include "core/core.h"

#include <math.h>
#include <pthread.h>
#include <string.h>

#define WORLD_READER_EPOCHS 64               /* distinct trims that readers may span at once */

typedef struct world_entry world_entry;
struct world_entry {
    terrain_chunk_coord coord;
    terrain_stacks *stacks;
    world_entry *next_in_bucket;
    world_entry *lru_prev, *lru_next;     /* most recently used at the head */
    int retained;
    uint32_t version;                     /* the world's commit count at its last commit; 0 = never */
    bool pinned;                          /* edited with no log to keep the edits: never evicted */
};

typedef struct world_stamp {
    terrain_chunk_coord coord;
    uint32_t version;                     /* 0 = an empty slot */
} world_stamp;

struct terrain_world {
    pthread_mutex_t lock;
    terrain_generation_desc generation;
    terrain_stacks *(*generate)(void *user, terrain_chunk_coord coord);
    void *generate_user;
    terrain_edit_log *edits;              /* replayed over generated chunks, or NULL */
    bool sea;                             /* edits let the sea in (terrain_world_desc.sea) */
    void (*amplify)(void *user, terrain_world *world, terrain_field *field);
    void *amplify_user;
    float amplify_reach[3];               /* metres (terrain_world_desc.amplify_reach) */
    void (*generated)(void *user, terrain_chunk_coord coord);   /* tests' seam (internal header) */
    void *generated_user;
    terrain_world_change *changes;        /* committed since the last terrain_world_take_changes */
    size_t change_count, change_capacity;
    size_t max_chunks;
    uint32_t commits;                     /* commits so far: the stamp of the newest (written
                                             atomically under the lock, read without it) */
    /* The stamps of evicted chunks that had commits (open addressing; a power of two). */
    world_stamp *stamps;
    size_t stamp_count, stamp_capacity;
    world_entry **buckets;
    size_t bucket_count;                  /* a power of two */
    size_t count, bytes;
    world_entry *lru_head, *lru_tail;
    /* The far terrain's watch (terrain__world_watch_surface): chunks inserted, committed or
     * evicted since it last took them, while watched. */
    bool surface_watched;
    terrain_chunk_coord *surface_changes;
    size_t surface_change_count, surface_change_capacity;
    /* Readers that span trims (background jobs): how many began in each epoch, and the stacks
     * trimmed while any of them may still hold a pointer. */
    uint64_t epoch;                       /* trims so far */
    struct { uint64_t epoch; int count; } readers[WORLD_READER_EPOCHS];
    int reader_epochs;
    struct { terrain_stacks *stacks; uint64_t epoch; } *graveyard;
    size_t graveyard_count, graveyard_capacity;
};

static uint64_t coord_hash(terrain_chunk_coord c) {
    return core_hash_combine(core_hash_u64((uint64_t)c.x), (uint64_t)c.z);
}

static bool coord_equal(terrain_chunk_coord a, terrain_chunk_coord b) {
    return a.x == b.x && a.z == b.z;
}

terrain_world *terrain_world_create(const terrain_world_desc *desc) {
    terrain_world *w = core_calloc(1, sizeof *w);
    pthread_mutex_init(&w->lock, NULL);
    w->generation = desc->generation;
    w->generate = desc->generate;
    w->generate_user = desc->generate_user;
    w->amplify = desc->amplify;
    w->amplify_user = desc->amplify_user;
    for (int a = 0; a < 3; a++)
        w->amplify_reach[a] = desc->amplify && desc->amplify_reach[a] > 0.0f ? desc->amplify_reach[a] : 0.0f;
    w->edits = desc->edits;
    w->sea = desc->generate == NULL || desc->sea;
    w->max_chunks = desc->max_chunks ? desc->max_chunks : 4096;
    w->bucket_count = 64;
    w->buckets = core_calloc(w->bucket_count, sizeof *w->buckets);
    return w;
}

void terrain_world_destroy(terrain_world *world) {
    if (!world) return;
    for (size_t i = 0; i < world->graveyard_count; i++) terrain_stacks_destroy(world->graveyard[i].stacks);
    core_free(world->graveyard, world->graveyard_capacity * sizeof *world->graveyard);
    core_free(world->changes, world->change_capacity * sizeof *world->changes);
    core_free(world->surface_changes, world->surface_change_capacity * sizeof *world->surface_changes);
    core_free(world->stamps, world->stamp_capacity * sizeof *world->stamps);
    for (world_entry *e = world->lru_head, *next; e; e = next) {
        next = e->lru_next;
        terrain_stacks_destroy(e->stacks);
        core_free(e, sizeof *e);
    }
    core_free(world->buckets, world->bucket_count * sizeof *world->buckets);
    pthread_mutex_destroy(&world->lock);
    core_free(world, sizeof *world);
}

/* ---- the map and the LRU list (lock held) ---------------------------------------------- */

static world_entry **find_slot(terrain_world *w, terrain_chunk_coord coord) {
    world_entry **slot = &w->buckets[coord_hash(coord) & (w->bucket_count - 1)];
    while (*slot && !coord_equal((*slot)->coord, coord)) slot = &(*slot)->next_in_bucket;
    return slot;
}

static void lru_unlink(terrain_world *w, world_entry *e) {
    if (e->lru_prev) e->lru_prev->lru_next = e->lru_next; else w->lru_head = e->lru_next;
    if (e->lru_next) e->lru_next->lru_prev = e->lru_prev; else w->lru_tail = e->lru_prev;
    e->lru_prev = e->lru_next = NULL;
}

static void lru_push_front(terrain_world *w, world_entry *e) {
    e->lru_prev = NULL;
    e->lru_next = w->lru_head;
    if (w->lru_head) w->lru_head->lru_prev = e; else w->lru_tail = e;
    w->lru_head = e;
}

static void touch(terrain_world *w, world_entry *e) {
    if (w->lru_head == e) return;
    lru_unlink(w, e);
    lru_push_front(w, e);
}

static void grow_buckets(terrain_world *w) {
    size_t old_count = w->bucket_count;
    world_entry **old = w->buckets;
    w->bucket_count = old_count * 2;
    w->buckets = core_calloc(w->bucket_count, sizeof *w->buckets);
    for (size_t b = 0; b < old_count; b++) {
        for (world_entry *e = old[b], *next; e; e = next) {
            next = e->next_in_bucket;
            world_entry **slot = &w->buckets[coord_hash(e->coord) & (w->bucket_count - 1)];
            e->next_in_bucket = *slot;
            *slot = e;
        }
    }
    core_free(old, old_count * sizeof *old);
}

/* ---- stamps of evicted chunks (lock held) ------------------------------------------------ */

static size_t stamp_slot(const terrain_world *w, terrain_chunk_coord coord) {
    size_t mask = w->stamp_capacity - 1, i = coord_hash(coord) & mask;
    while (w->stamps[i].version && !coord_equal(w->stamps[i].coord, coord)) i = (i + 1) & mask;
    return i;
}

static uint32_t stamp_of(const terrain_world *w, terrain_chunk_coord coord) {
    return w->stamp_capacity ? w->stamps[stamp_slot(w, coord)].version : 0;
}

static void keep_stamp(terrain_world *w, terrain_chunk_coord coord, uint32_t version) {
    if (!version) return;
    if ((w->stamp_count + 1) * 2 > w->stamp_capacity) {     /* at most half full */
        size_t old_capacity = w->stamp_capacity;
        world_stamp *old = w->stamps;
        w->stamp_capacity = old_capacity ? old_capacity * 2 : 64;
        w->stamps = core_calloc(w->stamp_capacity, sizeof *w->stamps);
        for (size_t i = 0; i < old_capacity; i++)
            if (old[i].version) w->stamps[stamp_slot(w, old[i].coord)] = old[i];
        core_free(old, old_capacity * sizeof *old);
    }
    size_t i = stamp_slot(w, coord);
    w->stamp_count += w->stamps[i].version == 0;
    w->stamps[i].coord = coord;
    w->stamps[i].version = version;
}

/* Lock held: a chunk whose stacks came, changed or went, for the far terrain's watch. */
static void note_surface(terrain_world *w, terrain_chunk_coord coord) {
    if (!w->surface_watched) return;
    w->surface_changes = core_grow(w->surface_changes, &w->surface_change_capacity, w->surface_change_count + 1,
                                   sizeof *w->surface_changes);
    w->surface_changes[w->surface_change_count++] = coord;
}

/* Inserts a freshly generated chunk unless another thread got there first; returns the entry
 * that is in the map (ours or theirs; a losing copy is freed), or NULL when the chunk was
 * committed after `started` (the commit count when our generation began): our copy may lack
 * that commit, so it is freed and the caller generates again. */
static world_entry *insert_or_get(terrain_world *w, terrain_chunk_coord coord, terrain_stacks *stacks,
                                  uint32_t started) {
    world_entry **slot = find_slot(w, coord);
    uint32_t version = stamp_of(w, coord);
    if (*slot || version > started) {
        terrain_stacks_destroy(stacks);
        return *slot;
    }
    world_entry *e = core_calloc(1, sizeof *e);
    e->coord = coord;
    e->stacks = stacks;
    e->version = version;
    *slot = e;
    lru_push_front(w, e);
    note_surface(w, coord);
    w->bytes += terrain_stacks_bytes(stacks);
    if (++w->count > w->bucket_count) grow_buckets(w);
    return e;
}

/* The chunk as generated, with its logged edits replayed over it. */
static terrain_stacks *generate(terrain_world *w, terrain_chunk_coord coord) {
    terrain_stacks *stacks = w->generate ? w->generate(w->generate_user, coord)
                                         : terrain_generate_chunk(&w->generation, coord);
    if (!w->edits || !stacks) return stacks;
    terrain_stacks *edited = terrain_edit_log_replay(w->edits, coord, stacks);
    if (!edited) return stacks;
    terrain_stacks_destroy(stacks);
    return edited;
}

/* The entry for `coord`, generated if needed, touched; returns with the lock held. */
static world_entry *acquire(terrain_world *w, terrain_chunk_coord coord) {
    pthread_mutex_lock(&w->lock);
    world_entry *e = *find_slot(w, coord);
    while (!e) {
        uint32_t started = w->commits;
        pthread_mutex_unlock(&w->lock);
        terrain_stacks *stacks = generate(w, coord);   /* outside the lock: slow, parallel */
        if (w->generated) w->generated(w->generated_user, coord);
        pthread_mutex_lock(&w->lock);
        e = insert_or_get(w, coord, stacks, started);
    }
    touch(w, e);
    return e;
}

/* ---- the API ---------------------------------------------------------------------------- */

const terrain_stacks *terrain_world_stacks(terrain_world *world, terrain_chunk_coord coord) {
    world_entry *e = acquire(world, coord);
    const terrain_stacks *stacks = e->stacks;
    pthread_mutex_unlock(&world->lock);
    return stacks;
}

void terrain_world_retain(terrain_world *world, terrain_chunk_coord coord) {
    world_entry *e = acquire(world, coord);
    e->retained++;
    pthread_mutex_unlock(&world->lock);
}

void terrain_world_release(terrain_world *world, terrain_chunk_coord coord) {
    pthread_mutex_lock(&world->lock);
    world_entry *e = *find_slot(world, coord);
    bool unmatched = !e || e->retained == 0;
    if (!unmatched) e->retained--;
    pthread_mutex_unlock(&world->lock);
    if (unmatched)
        core_warn("terrain", "release of chunk (%lld, %lld) that is not retained",
                  (long long)coord.x, (long long)coord.z);
}

/* ---- readers across trims (lock held) --------------------------------------------------- */

static uint64_t oldest_reader_epoch(const terrain_world *w) {
    uint64_t oldest = UINT64_MAX;
    for (int i = 0; i < w->reader_epochs; i++)
        if (w->readers[i].epoch < oldest) oldest = w->readers[i].epoch;
    return oldest;
}

/* Frees the stacks no reader can still hold: those buried in an epoch that has ended (a trim
 * since: frame readers are done) and before every active spanning reader began. */
static void bury_dead(terrain_world *w) {
    uint64_t oldest = oldest_reader_epoch(w);
    size_t kept = 0;
    for (size_t i = 0; i < w->graveyard_count; i++) {
        uint64_t epoch = w->graveyard[i].epoch;
        if (epoch < oldest && epoch < w->epoch) terrain_stacks_destroy(w->graveyard[i].stacks);
        else w->graveyard[kept++] = w->graveyard[i];
    }
    w->graveyard_count = kept;
}

/* Stacks that left the cache: freed once no reader can hold them. Readers within a frame are
 * done at the next trim; readers that span trims (read_begin) hold what was cached in their
 * epoch. */
static void bury(terrain_world *w, terrain_stacks *stacks) {
    w->graveyard = core_grow(w->graveyard, &w->graveyard_capacity, w->graveyard_count + 1, sizeof *w->graveyard);
    w->graveyard[w->graveyard_count].stacks = stacks;
    w->graveyard[w->graveyard_count++].epoch = w->epoch;
}

static void evict(terrain_world *w, world_entry *e) {
    *find_slot(w, e->coord) = e->next_in_bucket;
    lru_unlink(w, e);
    w->bytes -= terrain_stacks_bytes(e->stacks);
    keep_stamp(w, e->coord, e->version);
    note_surface(w, e->coord);
    /* Eviction runs in a trim, where no frame reader is left: only spanning readers matter. */
    if (w->reader_epochs > 0) bury(w, e->stacks);
    else terrain_stacks_destroy(e->stacks);
    core_free(e, sizeof *e);
    w->count--;
}

uint64_t terrain_world_read_begin(terrain_world *world) {
    pthread_mutex_lock(&world->lock);
    uint64_t epoch = world->epoch;
    int i = 0;
    while (i < world->reader_epochs && world->readers[i].epoch != epoch) i++;
    if (i == world->reader_epochs) {
        if (i == WORLD_READER_EPOCHS) {    /* absurdly old readers: count under the oldest */
            uint64_t oldest = oldest_reader_epoch(world);
            for (i = 0; world->readers[i].epoch != oldest; i++) {}
            epoch = oldest;
        } else {
            world->readers[i].epoch = epoch;
            world->readers[i].count = 0;
            world->reader_epochs++;
        }
    }
    world->readers[i].count++;
    pthread_mutex_unlock(&world->lock);
    return epoch;
}

void terrain_world_read_end(terrain_world *world, uint64_t token) {
    pthread_mutex_lock(&world->lock);
    for (int i = 0; i < world->reader_epochs; i++) {
        if (world->readers[i].epoch != token) continue;
        if (--world->readers[i].count == 0) world->readers[i] = world->readers[--world->reader_epochs];
        break;
    }
    bury_dead(world);
    pthread_mutex_unlock(&world->lock);
}

size_t terrain_world_trim(terrain_world *world) {
    pthread_mutex_lock(&world->lock);
    size_t evicted = 0;
    world_entry *e = world->lru_tail;
    while (world->count > world->max_chunks && e) {
        world_entry *prev = e->lru_prev;
        if (e->retained == 0 && !e->pinned) {
            evict(world, e);
            evicted++;
        }
        e = prev;
    }
    world->epoch++;
    bury_dead(world);
    pthread_mutex_unlock(&world->lock);
    return evicted;
}

size_t terrain_world_chunk_count(terrain_world *world) {
    pthread_mutex_lock(&world->lock);
    size_t count = world->count;
    pthread_mutex_unlock(&world->lock);
    return count;
}

size_t terrain_world_bytes(terrain_world *world) {
    pthread_mutex_lock(&world->lock);
    size_t bytes = world->bytes;
    pthread_mutex_unlock(&world->lock);
    return bytes;
}

bool terrain_world_has(terrain_world *world, terrain_chunk_coord coord) {
    pthread_mutex_lock(&world->lock);
    bool has = *find_slot(world, coord) != NULL;
    pthread_mutex_unlock(&world->lock);
    return has;
}

const terrain_generation_desc *terrain_world_generation(const terrain_world *world) { return &world->generation; }

bool terrain__world_sea(const terrain_world *world, int32_t *sea_quanta) {
    double quanta = ((double)world->generation.sea_level - TERRAIN_FLOOR_Y) * TERRAIN__QUANTA_PER_METRE;
    if (!world->sea || !(quanta > 0.0)) return false;      /* a sea at or below the floor is none */
    *sea_quanta = quanta >= TERRAIN__COLUMN_MAX_QUANTA ? TERRAIN__COLUMN_MAX_QUANTA : (int32_t)llround(quanta);
    return true;
}

void terrain_world_set_max_chunks(terrain_world *world, size_t max_chunks) {
    pthread_mutex_lock(&world->lock);
    world->max_chunks = max_chunks ? max_chunks : 4096;
    pthread_mutex_unlock(&world->lock);
}

/* The stacks holding the column under world (x, z), and the column's place in them. */
static const terrain_stacks *column_at(terrain_world *world, double x, double z, int *i, int *k) {
    double column_x = floor(x / TERRAIN_COLUMN_SIZE), column_z = floor(z / TERRAIN_COLUMN_SIZE);
    double chunk_x = floor(column_x / TERRAIN_CHUNK_COLUMNS), chunk_z = floor(column_z / TERRAIN_CHUNK_COLUMNS);
    *i = (int)(column_x - chunk_x * TERRAIN_CHUNK_COLUMNS);
    *k = (int)(column_z - chunk_z * TERRAIN_CHUNK_COLUMNS);
    return terrain_world_stacks(world, (terrain_chunk_coord){ (int64_t)chunk_x, (int64_t)chunk_z });
}

terrain_material terrain_world_material_at(terrain_world *world, double x, double y, double z) {
    int i, k;
    const terrain_stacks *stacks = column_at(world, x, z, &i, &k);
    return terrain_stacks_material_at(stacks, i, k, (float)y);
}

float terrain_world_top(terrain_world *world, double x, double z) {
    int i, k;
    const terrain_stacks *stacks = column_at(world, x, z, &i, &k);
    return terrain_stacks_top(stacks, i, k);
}

bool terrain_world_has_sea(const terrain_world *world) { return world->sea; }

bool terrain_world_water_at(terrain_world *world, double x, double z, float *surface, float *ground) {
    int i, k;
    const terrain_stacks *stacks = column_at(world, x, z, &i, &k);
    float top = terrain_stacks_top(stacks, i, k), wet = terrain_stacks_surface(stacks, i, k);
    if (!(wet > top)) return false;   /* the highest non-air layer is solid: dry */
    if (surface) *surface = wet;
    if (ground) *ground = top;
    return true;
}

/* ---- edits -------------------------------------------------------------------------------- */

/* Lock held. One entry per chunk: a second commit widens the first's box. */
static void queue_change(terrain_world *w, const terrain_world_change *change) {
    for (size_t i = 0; i < w->change_count; i++) {
        terrain_world_change *c = &w->changes[i];
        if (!coord_equal(c->coord, change->coord)) continue;
        for (int a = 0; a < 2; a++) {
            if (change->column_min[a] < c->column_min[a]) c->column_min[a] = change->column_min[a];
            if (change->column_max[a] > c->column_max[a]) c->column_max[a] = change->column_max[a];
        }
        c->y_min = fminf(c->y_min, change->y_min);
        c->y_max = fmaxf(c->y_max, change->y_max);
        return;
    }
    w->changes = core_grow(w->changes, &w->change_capacity, w->change_count + 1, sizeof *w->changes);
    w->changes[w->change_count++] = *change;
}

void terrain_world_commit(terrain_world *world, terrain_chunk_coord coord, terrain_stacks *stacks,
                          terrain_edit_tool tool) {
    if (!stacks) {
        core_warn("terrain", "commit of chunk (%lld, %lld) without stacks: ignored", (long long)coord.x,
                  (long long)coord.z);
        return;
    }
    world_entry *e = acquire(world, coord);
    terrain_stacks *before = e->stacks;
    terrain_world_change change = { .coord = coord };
    bool differs = terrain__stacks_diff(before, stacks, &change);
    /* The log diffs under the world's lock: the log has its own and never calls back. */
    if (world->edits && differs) terrain_edit_log_record(world->edits, coord, tool, before, stacks);
    else if (differs) e->pinned = true;
    world->bytes += terrain_stacks_bytes(stacks) - terrain_stacks_bytes(before);
    e->stacks = stacks;
    e->version = __atomic_add_fetch(&world->commits, 1, __ATOMIC_RELEASE);   /* read unlocked too */
    bury(world, before);       /* a job of this frame may still read it: freed at a later trim */
    if (differs) queue_change(world, &change);
    if (differs) note_surface(world, coord);
    pthread_mutex_unlock(&world->lock);
}

/* Moves up to `capacity` of the `*count` queued items of `size` bytes at `queue` to `out`, oldest
 * first, and closes the gap: under the world's lock. */
static int take_queued(void *out, int capacity, void *queue, size_t *count, size_t size) {
    size_t n = capacity > 0 ? (size_t)capacity : 0;
    if (n > *count) n = *count;
    if (n) {
        memcpy(out, queue, n * size);
        memmove(queue, (char *)queue + n * size, (*count - n) * size);
    }
    *count -= n;
    return (int)n;
}

int terrain_world_take_changes(terrain_world *world, terrain_world_change *out, int capacity) {
    pthread_mutex_lock(&world->lock);
    int n = take_queued(out, capacity, world->changes, &world->change_count, sizeof *out);
    pthread_mutex_unlock(&world->lock);
    return n;
}

uint32_t terrain_world_chunk_version(terrain_world *world, terrain_chunk_coord coord) {
    pthread_mutex_lock(&world->lock);
    world_entry *e = *find_slot(world, coord);
    uint32_t version = e ? e->version : stamp_of(world, coord);   /* evicted: the stamp it kept */
    pthread_mutex_unlock(&world->lock);
    return version;
}

uint32_t terrain_world_commit_count(terrain_world *world) {
    return __atomic_load_n(&world->commits, __ATOMIC_ACQUIRE);   /* no lock: a reader asks often */
}

void terrain__world_on_generated(terrain_world *world, void (*fn)(void *user, terrain_chunk_coord coord),
                                  void *user) {
    world->generated = fn;
    world->generated_user = user;
}

void terrain__world_amplify(terrain_world *world, terrain_field *field) {
    if (world->amplify) world->amplify(world->amplify_user, world, field);
}

const float *terrain__world_amplify_reach(const terrain_world *world) { return world->amplify_reach; }

/* ---- the far terrain's view of the cache ------------------------------------------------- */

const terrain_stacks *terrain__world_cached(terrain_world *world, terrain_chunk_coord coord) {
    pthread_mutex_lock(&world->lock);
    world_entry *e = *find_slot(world, coord);
    const terrain_stacks *stacks = e ? e->stacks : NULL;   /* not touched: looking keeps nothing */
    pthread_mutex_unlock(&world->lock);
    return stacks;
}

const terrain_stacks *terrain__world_surface_stacks(terrain_world *world, terrain_chunk_coord coord) {
    const terrain_stacks *stacks = terrain__world_cached(world, coord);
    if (stacks || !world->edits || terrain_edit_log_entries(world->edits, coord) == 0) return stacks;
    return terrain_world_stacks(world, coord);
}

void terrain__world_watch_surface(terrain_world *world, bool on) {
    pthread_mutex_lock(&world->lock);
    world->surface_watched = on;
    world->surface_change_count = 0;
    pthread_mutex_unlock(&world->lock);
}

int terrain__world_take_surface_changes(terrain_world *world, terrain_chunk_coord *out, int capacity) {
    pthread_mutex_lock(&world->lock);
    int n = take_queued(out, capacity, world->surface_changes, &world->surface_change_count, sizeof *out);
    pthread_mutex_unlock(&world->lock);
    return n;
}
