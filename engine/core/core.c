/* core.c — logging, time, memory accounting, arenas and hashing (see core.h). */
#include "core.h"

#include <errno.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <sys/stat.h>
#include <unistd.h>

/* ---- logging ---------------------------------------------------------------------------- */

static _Atomic int log_min_level = CORE_LOG_INFO;
static const char *const log_level_names[] = { "debug", "info", "warn", "error" };

void core_log_set_level(core_log_level level) { atomic_store(&log_min_level, (int)level); }
core_log_level core_log_get_level(void) { return (core_log_level)atomic_load(&log_min_level); }

static void log_line(const char *level_name, const char *module, const char *fmt, va_list args) {
    /* Format the whole line first and write it with one call, so that lines from several
     * threads never interleave mid-line. */
    char line[1024];
    int head = snprintf(line, sizeof line, "[%s] %s: ", level_name, module ? module : "engine");
    if (head < 0) return;
    int body = vsnprintf(line + head, sizeof line - (size_t)head, fmt, args);
    size_t length = (size_t)head + (body < 0 ? 0 : (size_t)body);
    if (length > sizeof line - 2) length = sizeof line - 2; /* truncated: keep the newline */
    line[length++] = '\n';
    fwrite(line, 1, length, stderr);
}

void core_log(core_log_level level, const char *module, const char *fmt, ...) {
    if ((int)level < atomic_load_explicit(&log_min_level, memory_order_relaxed) ||
        level >= CORE_LOG_OFF)
        return;
    va_list args;
    va_start(args, fmt);
    log_line(log_level_names[level], module, fmt, args);
    va_end(args);
}

void core_fatal(const char *module, const char *fmt, ...) {
    va_list args;
    va_start(args, fmt);
    log_line("fatal", module, fmt, args);
    va_end(args);
    abort();
}

/* ---- time ------------------------------------------------------------------------------- */

uint64_t core_time_ns(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (uint64_t)ts.tv_sec * 1000000000ull + (uint64_t)ts.tv_nsec;
}

int core_cpu_count(void) {
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : (int)n;
}

/* ---- memory ----------------------------------------------------------------------------- */

static _Atomic size_t memory_in_use;

static void *checked(void *ptr, size_t size) {
    if (!ptr && size) core_fatal("core", "out of memory allocating %zu bytes", size);
    return ptr;
}

void *core_alloc(size_t size) {
    void *ptr = checked(malloc(size ? size : 1), size);
    atomic_fetch_add_explicit(&memory_in_use, size, memory_order_relaxed);
    return ptr;
}

void *core_alloc_aligned(size_t size, size_t align) {
    size_t rounded = (size + align - 1) & ~(align - 1); /* aligned_alloc wants a multiple */
    void *ptr = checked(aligned_alloc(align, rounded ? rounded : align), size);
    atomic_fetch_add_explicit(&memory_in_use, size, memory_order_relaxed);
    return ptr;
}

void *core_calloc(size_t count, size_t size) {
    if (size && count > SIZE_MAX / size) core_fatal("core", "calloc overflow: %zu × %zu", count, size);
    void *ptr = checked(calloc(count ? count : 1, size ? size : 1), count * size);
    atomic_fetch_add_explicit(&memory_in_use, count * size, memory_order_relaxed);
    return ptr;
}

void *core_realloc(void *ptr, size_t old_size, size_t new_size) {
    void *grown = checked(realloc(ptr, new_size ? new_size : 1), new_size);
    atomic_fetch_add_explicit(&memory_in_use, new_size, memory_order_relaxed);
    atomic_fetch_sub_explicit(&memory_in_use, old_size, memory_order_relaxed);
    return grown;
}

void core_free(void *ptr, size_t size) {
    if (!ptr) return;
    free(ptr);
    atomic_fetch_sub_explicit(&memory_in_use, size, memory_order_relaxed);
}

void *core__grow_slow(void *items, size_t *capacity, size_t needed, size_t item_size) {
    size_t grown = CORE_MAX(CORE_MAX(needed, *capacity * 2), (size_t)8);
    if (item_size && grown > SIZE_MAX / item_size) core_fatal("core", "array of %zu × %zu bytes overflows", grown, item_size);
    items = core_realloc(items, *capacity * item_size, grown * item_size);
    *capacity = grown;
    return items;
}

size_t core_memory_in_use(void) { return atomic_load_explicit(&memory_in_use, memory_order_relaxed); }

bool core_error_set(core_error *error, core_error_code code, const char *fmt, ...) {
    if (error) {
        error->code = code;
        va_list args;
        va_start(args, fmt);
        vsnprintf(error->message, sizeof error->message, fmt, args);
        va_end(args);
    }
    return false;
}

const char *core_error_code_name(core_error_code code) {
    static const char *const names[CORE_ERROR_CODE_COUNT] = {
        [CORE_ERROR_NONE] = "none",         [CORE_ERROR_IO] = "io",
        [CORE_ERROR_FORMAT] = "format",     [CORE_ERROR_VERSION] = "version",
        [CORE_ERROR_MISMATCH] = "mismatch", [CORE_ERROR_CORRUPT] = "corrupt",
        [CORE_ERROR_RANGE] = "range",       [CORE_ERROR_ARGUMENT] = "argument",
    };
    return (unsigned)code < CORE_ERROR_CODE_COUNT ? names[code] : "unknown";
}

char *core_strjoin(const char *a, const char *b) {
    size_t a_size = strlen(a), b_size = strlen(b);
    char *joined = core_alloc(a_size + b_size + 1);
    memcpy(joined, a, a_size);
    memcpy(joined + a_size, b, b_size + 1);
    return joined;
}

char *core_strdup(const char *s) {
    size_t size = strlen(s) + 1;
    return memcpy(core_alloc(size), s, size);
}

/* ---- arena ------------------------------------------------------------------------------ */

struct core_arena_block {
    core_arena_block *next;
    size_t size, used;
    alignas(max_align_t) unsigned char data[];
};

static core_arena_block *arena_block_new(size_t size) {
    core_arena_block *block = core_alloc(sizeof *block + size);
    block->next = NULL;
    block->size = size;
    block->used = 0;
    return block;
}

static void *arena_take(core_arena_block *block, size_t size, size_t align) {
    uintptr_t base = (uintptr_t)block->data;
    uintptr_t start = (base + block->used + (align - 1)) & ~(uintptr_t)(align - 1);
    if (start + size > base + block->size) return NULL;
    block->used = start + size - base;
    return (void *)start;
}

void *core_arena_alloc(core_arena *arena, size_t size, size_t align) {
    if (align == 0) align = 1;
    /* Walk forward through blocks kept from before the last reset, then grow. */
    while (arena->current) {
        void *ptr = arena_take(arena->current, size, align);
        if (ptr) return ptr;
        if (!arena->current->next) break;
        arena->current = arena->current->next;
        arena->current->used = 0;
    }
    size_t block_size = arena->block_size ? arena->block_size : 64 * 1024;
    if (size + align > block_size) block_size = size + align;
    core_arena_block *block = arena_block_new(block_size);
    if (arena->current) {
        block->next = arena->current->next;
        arena->current->next = block;
    } else {
        arena->first = block;
    }
    arena->current = block;
    return arena_take(block, size, align);
}

void core_arena_reset(core_arena *arena) {
    arena->current = arena->first;
    if (arena->current) arena->current->used = 0;
}

void core_arena_release(core_arena *arena) {
    for (core_arena_block *block = arena->first, *next; block; block = next) {
        next = block->next;
        core_free(block, sizeof *block + block->size);
    }
    arena->first = arena->current = NULL;
}

size_t core_arena_capacity(const core_arena *arena) {
    size_t total = 0;
    for (const core_arena_block *block = arena->first; block; block = block->next) total += block->size;
    return total;
}

/* ---- hashing ---------------------------------------------------------------------------- */

uint64_t core_hash_bytes(const void *data, size_t size, uint64_t seed) {
    /* FNV-1a over the bytes, then a strong finaliser: FNV alone mixes its last bytes weakly. */
    const unsigned char *bytes = data;
    uint64_t h = 0xcbf29ce484222325ull ^ core_hash_u64(seed);
    for (size_t i = 0; i < size; i++) h = (h ^ bytes[i]) * 0x100000001b3ull;
    return core_hash_u64(h ^ size);
}

bool core_make_dirs(const char *path) {
    if (!path || !*path) {
        errno = ENOENT;
        return false;
    }
    size_t length = strlen(path);
    char *copy = core_strdup(path);
    bool ok = true;
    /* Each prefix that ends before a '/' (and the whole path) in turn; existing ones are fine. */
    for (size_t i = 1; i <= length && ok; i++) {
        if (copy[i] != '/' && copy[i] != '\0') continue;
        char saved = copy[i];
        copy[i] = '\0';
        if (mkdir(copy, 0777) != 0 && errno != EEXIST) ok = false;
        copy[i] = saved;
    }
    struct stat info;
    if (ok && stat(path, &info) != 0) ok = false;                 /* errno from stat */
    else if (ok && !S_ISDIR(info.st_mode)) errno = ENOTDIR, ok = false;
    core_free(copy, length + 1);
    return ok;
}
