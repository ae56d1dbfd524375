/* core.h — the engine's base layer: logging, time, memory accounting, arenas, hashing and
 * command-line options. Everything else in engine/ and modules/ includes this; it includes
 * nothing of ours.
 *
 * LOGGING
 *     core_log(CORE_LOG_WARN, "ecs", "component %s registered twice", name);
 *     core_info("jobs", "%d threads", n);          // shorthands: core_debug/info/warn/log_error
 *   Lines go to stderr as "[warn] ecs: component … registered twice". Thread-safe: one line is
 *   written with one call, so lines from different threads never interleave mid-line.
 *
 * ERRORS
 *   Every public function that can fail on outside input (a file, a device's bytes, a script, a
 *   command line, a desc) takes a trailing `core_error *error` (may be NULL) and returns false or
 *   NULL on failure, with error->code saying what kind of failure it was and error->message saying
 *   what and where, in a sentence for a person ("world/seed.json: line 3, column 14: expected
 *   ':'"). The library does not log it: the caller decides (a program prints it and exits, a game
 *   shows it, a test asserts the code). On success the error is left as it was.
 *       core_error error = {0};
 *       if (!terrain_field_read(path, &field, &error)) {
 *           core_log_error("export", "%s", error.message);
 *           return error.code == CORE_ERROR_IO ? 1 : 2;
 *       }
 *   Codes (zero is CORE_ERROR_NONE; tests assert the code, not the message):
 *     CORE_ERROR_IO        a file or folder cannot be opened, read, written, renamed or created
 *     CORE_ERROR_FORMAT    the content is malformed: bad syntax, bad magic, a missing field, a
 *                          value of the wrong type, an unknown name or keyword
 *     CORE_ERROR_VERSION   well-formed, but a version (or kind of file) this code does not read
 *     CORE_ERROR_MISMATCH  well-formed, but of something other than the caller asked for: a
 *                          world folder or edit file of another world (another seed or
 *                          generator key), a chunk file that holds another chunk
 *     CORE_ERROR_CORRUPT   a checksum does not match, or the content is truncated or inconsistent
 *                          with itself (sizes that disagree, a record past the end)
 *     CORE_ERROR_RANGE     a value is out of its allowed range (a size too big, a negative count)
 *     CORE_ERROR_ARGUMENT  a bad argument from the caller: a NULL or empty name, a desc field
 *                          that makes no sense, a request the object's state cannot serve
 *   core_error_set(error, code, fmt, …) fills one (NULL-safe, returns false so that a function
 *   can `return core_error_set(…);`); core_error_code_name(code) is "io", "format", ….
 *
 * TIME
 *     uint64_t t0 = core_time_ns();   // monotonic nanoseconds, vDSO-fast (~20 ns)
 *
 * MEMORY
 *   core_alloc/core_calloc/core_realloc/core_free wrap the C allocator and keep a global count of
 *   live bytes (core_memory_in_use), which the trace shows as a counter. They never return NULL:
 *   running out of memory is fatal and names the size that failed. core_free takes the size the
 *   block was allocated with (the caller always knows it; it keeps the count exact for free).
 *
 *   core_arena is a bump allocator for per-frame scratch: allocate, then reset all at once.
 *       core_arena a = {0};                      // zero-init = empty; grows in blocks on demand
 *       float *xs = core_arena_alloc(&a, n * sizeof *xs, alignof(float));
 *       core_arena_reset(&a);                    // keeps the blocks for the next frame
 *       core_arena_release(&a);                  // returns them
 *
 * HASHING
 *   Random numbers in the world come from hashes of coordinates, never from a shared generator
 *   (DESIGN.md, Determinism): core_hash_u64(x) is a strong 64-bit mix (bijective),
 *   core_hash_combine folds values in order, core_hash_bytes hashes a buffer (FNV-1a + mix).
 *
 * JSON
 *   core_json_parse reads RFC 8259 JSON into a tree of core_json_value allocated from an arena,
 *   so one core_arena_release frees it all. Bad input is CORE_ERROR_FORMAT with a message that
 *   gives line and column ("line 3, column 14: expected ':' after object key"); nesting is
 *   capped at CORE_JSON_MAX_DEPTH, and the parser never reads outside [text, text + size).
 *       core_arena arena = {0};
 *       core_json_value *root;
 *       core_error error = {0};
 *       if (!core_json_parse(text, size, &arena, &root, &error)) core_warn("io", "%s", error.message);
 *       double ts = core_json_number_or(core_json_get(event, "ts"), 0.0);
 *       core_arena_release(&arena);
 *   core_json_write_string writes a C string to a FILE * as a quoted, escaped JSON string.
 *
 * COMMAND LINES
 *   Every program parses its flags through core_cli_parse so that they all behave alike: "--name
 *   value" or "--name=value", --help prints the usage and exits 0, an unknown flag or bad value
 *   prints a message naming it plus the usage and exits 2. CORE_COMMON_OPTIONS adds the flags
 *   every program has (--threads N, --trace FILE).
 *       core_common_args common = {0};
 *       int frames = 100;
 *       core_option options[] = {
 *           CORE_COMMON_OPTIONS(common),
 *           { .name = "frames", .kind = CORE_OPTION_INT, .value = &frames, .min = 1,
 *             .max = 1000000, .metavar = "N", .help = "frames to run" },
 *       };
 *       core_cli cli = { .program = "demo", .summary = "…", .options = options,
 *                        .option_count = CORE_COUNTOF(options) };
 *       int rc = core_cli_parse(&cli, argc, argv);
 *       if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
 */
#ifndef CORE_H
#define CORE_H

#include <stdalign.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define CORE_COUNTOF(a) (sizeof(a) / sizeof((a)[0]))
#define CORE_MIN(a, b) ((a) < (b) ? (a) : (b))
#define CORE_MAX(a, b) ((a) > (b) ? (a) : (b))
#define CORE_PRINTF(fmt_index, first_arg) __attribute__((format(printf, fmt_index, first_arg)))

/* ---- logging ---------------------------------------------------------------------------- */

typedef enum core_log_level {
    CORE_LOG_DEBUG,
    CORE_LOG_INFO,
    CORE_LOG_WARN,
    CORE_LOG_ERROR,
    CORE_LOG_OFF,
} core_log_level;

void core_log(core_log_level level, const char *module, const char *fmt, ...) CORE_PRINTF(3, 4);
/* Lines below `level` are dropped. Default: CORE_LOG_INFO. */
void core_log_set_level(core_log_level level);
core_log_level core_log_get_level(void);

#define core_debug(module, ...) core_log(CORE_LOG_DEBUG, module, __VA_ARGS__)
#define core_info(module, ...) core_log(CORE_LOG_INFO, module, __VA_ARGS__)
#define core_warn(module, ...) core_log(CORE_LOG_WARN, module, __VA_ARGS__)
#define core_log_error(module, ...) core_log(CORE_LOG_ERROR, module, __VA_ARGS__)

/* ---- errors ---------------------------------------------------------------------------- */

/* What kind of failure; see ERRORS in the doc block above. Zero is "no error". */
typedef enum core_error_code {
    CORE_ERROR_NONE = 0,
    CORE_ERROR_IO,
    CORE_ERROR_FORMAT,
    CORE_ERROR_VERSION,
    CORE_ERROR_MISMATCH,
    CORE_ERROR_CORRUPT,
    CORE_ERROR_RANGE,
    CORE_ERROR_ARGUMENT,
    CORE_ERROR_CODE_COUNT,
} core_error_code;

typedef struct core_error {
    core_error_code code;
    char message[256];   /* for a person: what was wrong and where (the file, the line) */
} core_error;

/* Sets error->code and formats error->message (when error is not NULL); returns false. */
bool core_error_set(core_error *error, core_error_code code, const char *fmt, ...) CORE_PRINTF(3, 4);
/* "none", "io", "format", "version", "mismatch", "corrupt", "range", "argument"; "unknown" for
 * any other value. */
const char *core_error_code_name(core_error_code code);

/* Prints "fatal: module: message" and aborts. For states the program cannot go on from
 * (out of memory); never for bad input, which gets an error and a defined outcome. */
_Noreturn void core_fatal(const char *module, const char *fmt, ...) CORE_PRINTF(2, 3);

/* ---- time ------------------------------------------------------------------------------- */

uint64_t core_time_ns(void);                      /* CLOCK_MONOTONIC, nanoseconds */
static inline double core_ns_to_ms(uint64_t ns) { return (double)ns * 1e-6; }
int core_cpu_count(void);                         /* online cores, at least 1 */

/* ---- memory ----------------------------------------------------------------------------- */

void *core_alloc(size_t size);
void *core_calloc(size_t count, size_t size);
void *core_realloc(void *ptr, size_t old_size, size_t new_size);
void core_free(void *ptr, size_t size);
/* Returns `items` with room for at least `needed` items of `item_size` bytes, growing the
 * capacity by doubling (to at least 8) so that appending one at a time costs O(1) amortised;
 * updates *capacity. The new items are not initialised. The one growth policy of the engine. */
void *core__grow_slow(void *items, size_t *capacity, size_t needed, size_t item_size);
static inline void *core_grow(void *items, size_t *capacity, size_t needed, size_t item_size) {
    /* Inline: on hot append paths the array is almost always big enough already. */
    return needed <= *capacity ? items : core__grow_slow(items, capacity, needed, item_size);
}
/* Aligned to `align` (a power of two, at least sizeof(void *)); free with core_free. */
void *core_alloc_aligned(size_t size, size_t align);
size_t core_memory_in_use(void);                  /* live bytes through core_alloc & co. */
char *core_strdup(const char *s);                 /* free with core_free(p, strlen(p) + 1) */
char *core_strjoin(const char *a, const char *b); /* a then b; free like core_strdup's */
/* Creates the folder and any missing parents (mkdir -p); true when it exists afterwards as a
 * folder. On failure errno says why. */
bool core_make_dirs(const char *path);

typedef struct core_arena_block core_arena_block;
typedef struct core_arena {
    core_arena_block *first;    /* blocks, oldest first; kept across resets */
    core_arena_block *current;  /* block being filled */
    size_t block_size;          /* 0 = 64 KiB; larger requests get a block of their own size */
} core_arena;

void *core_arena_alloc(core_arena *arena, size_t size, size_t align);
void core_arena_reset(core_arena *arena);
void core_arena_release(core_arena *arena);
size_t core_arena_capacity(const core_arena *arena);

/* ---- hashing ---------------------------------------------------------------------------- */

static inline uint64_t core_hash_u64(uint64_t x) {
    /* A bijective 64-bit finaliser (the splitmix64 output function's constants). */
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ull;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebull;
    x ^= x >> 31;
    return x;
}
static inline uint64_t core_hash_combine(uint64_t seed, uint64_t value) {
    return core_hash_u64(seed ^ (value + 0x9e3779b97f4a7c15ull + (seed << 6) + (seed >> 2)));
}
uint64_t core_hash_bytes(const void *data, size_t size, uint64_t seed);

/* ---- command lines ---------------------------------------------------------------------- */

typedef enum core_option_kind {
    CORE_OPTION_FLAG,    /* bool *: present = true */
    CORE_OPTION_INT,     /* int *: checked against [min, max] */
    CORE_OPTION_DOUBLE,  /* double *: checked against [min_double, max_double] unless both 0 */
    CORE_OPTION_STRING,  /* const char **: points into argv */
} core_option_kind;

typedef struct core_option {
    const char *name;    /* without the leading "--" */
    core_option_kind kind;
    void *value;
    const char *metavar; /* shown in the usage: --threads N */
    const char *help;
    int min, max;        /* CORE_OPTION_INT bounds, inclusive (both 0: any int) */
    double min_double, max_double;
} core_option;

typedef struct core_cli {
    const char *program;           /* name in the usage line */
    const char *summary;           /* one line on what the program does */
    const core_option *options;
    int option_count;
    /* Positional arguments (e.g. a file): pointers into argv are stored in positional[]. */
    const char *positional_name;   /* shown in the usage line; NULL = none accepted */
    const char **positional;
    int positional_min, positional_max;
    int *positional_count;
} core_cli;

enum { CORE_CLI_OK = 0, CORE_CLI_HELP = 1, CORE_CLI_ERROR = 2 };

/* Returns CORE_CLI_OK, CORE_CLI_HELP (usage printed to stdout) or CORE_CLI_ERROR (a message
 * naming the bad argument and the usage printed to stderr). The caller exits 0 or 2. */
int core_cli_parse(const core_cli *cli, int argc, char **argv);
void core_cli_print_usage(const core_cli *cli, void *file /* FILE * */);

typedef struct core_common_args {
    int threads;               /* 0 = one per core */
    const char *trace_path;    /* NULL = tracing off */
} core_common_args;

#define CORE_COMMON_OPTIONS(args)                                                             \
    { .name = "threads", .kind = CORE_OPTION_INT, .value = &(args).threads, .metavar = "N",   \
      .min = 0, .max = 256, .help = "threads, the main one included (0 = one per core)" },    \
    { .name = "trace", .kind = CORE_OPTION_STRING, .value = &(args).trace_path,               \
      .metavar = "FILE", .help = "write a Chrome trace (open in ui.perfetto.dev)" }

/* ---- JSON ------------------------------------------------------------------------------- */

#define CORE_JSON_MAX_DEPTH 256   /* nested arrays/objects; deeper input is an error */

typedef enum core_json_type {
    CORE_JSON_NULL,
    CORE_JSON_BOOL,
    CORE_JSON_NUMBER,
    CORE_JSON_STRING,
    CORE_JSON_ARRAY,
    CORE_JSON_OBJECT,
} core_json_type;

/* UTF-8, NUL-terminated for convenience; `length` counts the bytes (a \u0000 escape may put a
 * NUL inside). */
typedef struct core_json_string {
    const char *chars;
    size_t length;
} core_json_string;

typedef struct core_json_value core_json_value;
struct core_json_value {
    core_json_type type;
    union {
        bool boolean;
        double number;
        core_json_string string;
        struct { core_json_value *items; size_t count; } array;
        /* keys[i] names values[i], in file order; duplicates are kept. */
        struct { core_json_string *keys; core_json_value *values; size_t count; } object;
    };
};

/* Parses text[0, size) (no NUL needed). On success *out is the root, allocated from `arena`; on
 * failure *out is NULL, `error` (may be NULL) is CORE_ERROR_FORMAT with a message that starts
 * "line L, column C: " (from 1; the column counts UTF-8 characters), and whatever was allocated
 * stays in the arena for the caller's release. */
bool core_json_parse(const char *text, size_t size, core_arena *arena, core_json_value **out,
                     core_error *error);
/* The member `key` of an object (the last one if repeated); NULL when absent or not an object. */
const core_json_value *core_json_get(const core_json_value *object, const char *key);
/* The number or string a value holds, or `fallback` when it is NULL or of another type. */
double core_json_number_or(const core_json_value *value, double fallback);
const char *core_json_string_or(const core_json_value *value, const char *fallback);
/* Whether a value is a string equal to `text`. */
bool core_json_string_equals(const core_json_value *value, const char *text);
/* Writes `s` quoted and escaped; invalid UTF-8 becomes U+FFFD so the output stays valid JSON. */
void core_json_write_string(void *file /* FILE * */, const char *s);

#endif /* CORE_H */
