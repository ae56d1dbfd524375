/* gfx_pool.c — slots with generations behind gfx's handles (sokol_gfx's pools): a handle is
 * generation << 16 | slot; destroying bumps the slot's generation, so old copies of the handle
 * stop matching, and freed slots are reused first in, first out. */
#include "gfx_internal.h"

#include "core/core.h"

#include <assert.h>
#include <string.h>

static uint32_t gfx_pool_slot(uint32_t id) { return id & (GFX_POOL_MAX_SLOTS - 1); }
static uint16_t gfx_pool_generation(uint32_t id) { return (uint16_t)(id >> GFX_POOL_SLOT_BITS); }

void gfx__pool_init(gfx_pool *pool, const char *kind, size_t entry_size, uint16_t first_generation) {
    *pool = (gfx_pool){ .kind = kind, .entry_size = entry_size, .count = 1,
                        .first_generation = first_generation ? first_generation : 1 };
}

void gfx__pool_destroy(gfx_pool *pool) {
    core_free(pool->entries, pool->capacity * pool->entry_size);
    core_free(pool->generations, pool->capacity * sizeof *pool->generations);
    core_free(pool->next_free, pool->capacity * sizeof *pool->next_free);
    core_free(pool->live, pool->capacity * sizeof *pool->live);
    *pool = (gfx_pool){ 0 };
}

static void gfx_pool_grow(gfx_pool *pool) {
    uint32_t old = pool->capacity, capacity = old ? old * 2 : 64;
    if (capacity > GFX_POOL_MAX_SLOTS) capacity = GFX_POOL_MAX_SLOTS;
    pool->entries = core_realloc(pool->entries, old * pool->entry_size, capacity * pool->entry_size);
    pool->generations = core_realloc(pool->generations, old * sizeof *pool->generations,
                                     capacity * sizeof *pool->generations);
    pool->next_free = core_realloc(pool->next_free, old * sizeof *pool->next_free,
                                   capacity * sizeof *pool->next_free);
    pool->live = core_realloc(pool->live, old * sizeof *pool->live, capacity * sizeof *pool->live);
    pool->capacity = capacity;
}

uint32_t gfx__pool_alloc(gfx_pool *pool, void **entry) {
    uint32_t slot;
    if (pool->free_head) {
        slot = pool->free_head;
        pool->free_head = pool->next_free[slot];
        if (!pool->free_head) pool->free_tail = 0;
    } else {
        if (pool->count >= GFX_POOL_MAX_SLOTS) {
            core_log_error("gfx", "more than %u live %ss: none made", GFX_POOL_MAX_SLOTS - 1, pool->kind);
            return 0;
        }
        if (pool->count >= pool->capacity) gfx_pool_grow(pool);
        slot = pool->count++;
        pool->generations[slot] = pool->first_generation;
    }
    pool->live[slot] = true;
    pool->live_count++;
    uint8_t *bytes = pool->entries + slot * pool->entry_size;
    memset(bytes, 0, pool->entry_size);
    *entry = bytes;
    return (uint32_t)pool->generations[slot] << GFX_POOL_SLOT_BITS | slot;
}

void *gfx__pool_lookup(const gfx_pool *pool, uint32_t id) {
    uint32_t slot = gfx_pool_slot(id);
    if (slot == 0 || slot >= pool->count || !pool->live[slot]) return NULL;
    if (pool->generations[slot] != gfx_pool_generation(id)) return NULL;
    return pool->entries + slot * pool->entry_size;
}

void gfx__pool_free(gfx_pool *pool, uint32_t id) {
    uint32_t slot = gfx_pool_slot(id);
    pool->live[slot] = false;
    pool->live_count--;
    /* Generation 0 is skipped so that no live handle of slot s is ever the same id twice in a
     * row; the ids of a slot cycle through 65 535 generations. */
    uint16_t next = (uint16_t)(pool->generations[slot] + 1);
    pool->generations[slot] = next ? next : 1;
    pool->next_free[slot] = 0;
    if (pool->free_tail) pool->next_free[pool->free_tail] = slot;
    else pool->free_head = slot;
    pool->free_tail = slot;
}

void gfx__pool_report(gfx_pool *pool, uint32_t id, const char *call) {
    const char *kind = pool ? pool->kind : "object";
    const char *what = id == 0 ? "zero" : !pool ? "context-less" : "stale";
#ifndef NDEBUG
    core_log_error("gfx", "%s: %s %s handle 0x%08x (destroyed, or never made)", call, what, kind, id);
    assert(!"a stale or zero gfx handle was used");
#else
    if (pool && pool->stale_reported) return;
    if (pool) pool->stale_reported = true;
    core_log_error("gfx", "%s: %s %s handle 0x%08x (destroyed, or never made); ignored, as every "
               "other such %s handle will be, without another message", call, what, kind, id, kind);
#endif
}
