/* Tests of engine/core: command lines, arenas, memory accounting, hashing, errors. */
#include "core/core.h"
#include "test.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* ---- command lines ---------------------------------------------------------------------- */

typedef struct parsed {
    core_common_args common;
    int frames;
    double speed;
    bool fly;
    const char *files[2];
    int file_count;
} parsed;

static int parse(parsed *out, int argc, char **argv) {
    *out = (parsed){ .frames = 10, .speed = 1.0 };
    core_option options[] = {
        CORE_COMMON_OPTIONS(out->common),
        { .name = "frames", .kind = CORE_OPTION_INT, .value = &out->frames, .min = 1, .max = 100 },
        { .name = "speed", .kind = CORE_OPTION_DOUBLE, .value = &out->speed, .min_double = 0.5, .max_double = 8 },
        { .name = "fly", .kind = CORE_OPTION_FLAG, .value = &out->fly },
    };
    core_cli cli = { .program = "test", .options = options, .option_count = (int)CORE_COUNTOF(options),
                     .positional_name = "FILE", .positional = out->files, .positional_min = 0,
                     .positional_max = 2, .positional_count = &out->file_count };
    return core_cli_parse(&cli, argc, argv);
}

#define ARGS(...) ((char *[]){ "test", __VA_ARGS__ })
#define ARGC(...) ((int)(sizeof((char *[]){ "test", __VA_ARGS__ }) / sizeof(char *)))
#define PARSE(out, ...) parse(out, ARGC(__VA_ARGS__), ARGS(__VA_ARGS__))

Test(core_cli, values_in_both_spellings) {
    parsed p;
    cr_assert_eq(PARSE(&p, "--frames", "42", "--speed=2.5", "--fly", "--threads=3", "a.json"), CORE_CLI_OK);
    cr_expect_eq(p.frames, 42);
    cr_expect_float_eq(p.speed, 2.5, 1e-12);
    cr_expect(p.fly);
    cr_expect_eq(p.common.threads, 3);
    cr_expect_null(p.common.trace_path);
    cr_assert_eq(p.file_count, 1);
    cr_expect_str_eq(p.files[0], "a.json");
}

Test(core_cli, defaults_stay_when_absent) {
    parsed p;
    cr_assert_eq(parse(&p, 1, ARGS(NULL)), CORE_CLI_OK);
    cr_expect_eq(p.frames, 10);
    cr_expect_not(p.fly);
    cr_expect_eq(p.file_count, 0);
}

Test(core_cli, bad_input_is_a_usage_error) {
    parsed p;
    cr_expect_eq(PARSE(&p, "--nope"), CORE_CLI_ERROR);
    cr_expect_eq(PARSE(&p, "-x"), CORE_CLI_ERROR);
    cr_expect_eq(PARSE(&p, "--frames"), CORE_CLI_ERROR);          /* value missing */
    cr_expect_eq(PARSE(&p, "--frames", "ten"), CORE_CLI_ERROR);   /* not a number */
    cr_expect_eq(PARSE(&p, "--frames", "12x"), CORE_CLI_ERROR);   /* trailing junk */
    cr_expect_eq(PARSE(&p, "--frames", "0"), CORE_CLI_ERROR);     /* below min */
    cr_expect_eq(PARSE(&p, "--frames", "101"), CORE_CLI_ERROR);   /* above max */
    cr_expect_eq(PARSE(&p, "--frames", "99999999999999999999"), CORE_CLI_ERROR);
    cr_expect_eq(PARSE(&p, "--speed", "nan"), CORE_CLI_ERROR);
    cr_expect_eq(PARSE(&p, "--speed", "9"), CORE_CLI_ERROR);
    cr_expect_eq(PARSE(&p, "--fly=yes"), CORE_CLI_ERROR);         /* a flag takes no value */
    cr_expect_eq(PARSE(&p, "--trace", ""), CORE_CLI_ERROR);       /* empty path */
    cr_expect_eq(PARSE(&p, "a", "b", "c"), CORE_CLI_ERROR);       /* too many files */
    cr_expect_eq(PARSE(&p, "--threads", "257"), CORE_CLI_ERROR);
}

Test(core_cli, help_and_end_of_options) {
    parsed p;
    cr_expect_eq(PARSE(&p, "--frames", "5", "--help"), CORE_CLI_HELP);
    cr_assert_eq(PARSE(&p, "--", "--fly"), CORE_CLI_OK); /* after "--" it is a file name */
    cr_expect_not(p.fly);
    cr_assert_eq(p.file_count, 1);
    cr_expect_str_eq(p.files[0], "--fly");
}

/* ---- arena ------------------------------------------------------------------------------ */

Test(core_arena, aligned_disjoint_and_reused_after_reset) {
    core_arena arena = { .block_size = 256 };
    char *a = core_arena_alloc(&arena, 10, 1);
    double *b = core_arena_alloc(&arena, sizeof(double) * 4, alignof(double));
    char *c = core_arena_alloc(&arena, 64, 64);
    cr_expect_eq((uintptr_t)b % alignof(double), 0u);
    cr_expect_eq((uintptr_t)c % 64, 0u);
    cr_expect(b >= (double *)(a + 10) || (char *)(b + 4) <= a, "allocations overlap");
    memset(a, 1, 10);
    memset(b, 2, sizeof(double) * 4);
    memset(c, 3, 64);
    cr_expect_eq(a[9], 1);

    /* A request larger than the block size gets a block of its own. */
    char *big = core_arena_alloc(&arena, 1000, 16);
    memset(big, 4, 1000);
    size_t capacity = core_arena_capacity(&arena);
    cr_expect_geq(capacity, 1000u + 256u);

    /* After a reset the same blocks serve again: no growth for the same pattern. */
    for (int frame = 0; frame < 10; frame++) {
        core_arena_reset(&arena);
        core_arena_alloc(&arena, 10, 1);
        core_arena_alloc(&arena, sizeof(double) * 4, alignof(double));
        core_arena_alloc(&arena, 64, 64);
        core_arena_alloc(&arena, 1000, 16);
    }
    cr_expect_eq(core_arena_capacity(&arena), capacity);
    core_arena_release(&arena);
    cr_expect_eq(core_arena_capacity(&arena), 0u);
}

/* ---- memory accounting ------------------------------------------------------------------ */

Test(core_memory, live_bytes_follow_allocations) {
    size_t before = core_memory_in_use();
    void *a = core_alloc(1000);
    char *b = core_calloc(10, 30);
    cr_expect_eq(core_memory_in_use() - before, 1300u);
    b = core_realloc(b, 300, 500);
    cr_expect_eq(core_memory_in_use() - before, 1500u);
    void *c = core_alloc_aligned(100, 64);
    cr_expect_eq((uintptr_t)c % 64, 0u);
    core_free(c, 100);
    core_free(a, 1000);
    core_free(b, 500);
    cr_expect_eq(core_memory_in_use(), before);
}

Test(core_memory, grow_keeps_items_and_doubles) {
    size_t before = core_memory_in_use();
    int *items = NULL;
    size_t capacity = 0, reallocations = 0;
    for (int i = 0; i < 1000; i++) {
        size_t old = capacity;
        items = core_grow(items, &capacity, (size_t)i + 1, sizeof *items);
        if (capacity != old) {
            reallocations++;
            /* Never less than 8, and at least double the old capacity. */
            cr_expect_geq(capacity, old * 2 > 8 ? old * 2 : 8);
        }
        cr_assert_geq(capacity, (size_t)i + 1);
        items[i] = i * 3;
    }
    for (int i = 0; i < 1000; i++) cr_assert_eq(items[i], i * 3, "item %d lost in a move", i);
    /* 8, 16, …, 1024: eight reallocations for a thousand appends. */
    cr_expect_eq(reallocations, 8u);
    cr_expect_eq(capacity, 1024u);
    cr_expect_eq(core_memory_in_use() - before, 1024 * sizeof *items);
    /* Asking for less than there is changes nothing. */
    int *same = core_grow(items, &capacity, 10, sizeof *items);
    cr_expect_eq(same, items);
    cr_expect_eq(capacity, 1024u);
    core_free(items, capacity * sizeof *items);
    cr_expect_eq(core_memory_in_use(), before);
}

/* ---- hashing ---------------------------------------------------------------------------- */

Test(core_hash, mixing_is_bijective_on_a_sample_and_avalanches) {
    enum { N = 1 << 16 };
    uint64_t *seen = malloc(N * sizeof *seen);
    for (uint64_t i = 0; i < N; i++) seen[i] = core_hash_u64(i);
    /* Distinct inputs, distinct outputs (the finaliser is a bijection). */
    for (uint64_t i = 0; i < N; i++)
        for (uint64_t j = i + 1; j < i + 64 && j < N; j++) cr_assert_neq(seen[i], seen[j]);
    /* Flipping one input bit flips about half the output bits: mean within 32 ± 1. */
    double flipped = 0;
    for (uint64_t i = 0; i < 4096; i++)
        for (int bit = 0; bit < 64; bit++)
            flipped += __builtin_popcountll(core_hash_u64(i) ^ core_hash_u64(i ^ (1ull << bit)));
    flipped /= 4096.0 * 64.0;
    cr_expect(flipped > 31.0 && flipped < 33.0, "mean flipped bits %.2f", flipped);
    free(seen);
}

Test(core_hash, bytes_depend_on_every_byte_seed_and_length) {
    const char text[] = "terrain chunk";
    uint64_t h = core_hash_bytes(text, sizeof text - 1, 7);
    cr_expect_eq(h, core_hash_bytes(text, sizeof text - 1, 7));
    cr_expect_neq(h, core_hash_bytes(text, sizeof text - 1, 8));
    cr_expect_neq(h, core_hash_bytes(text, sizeof text - 2, 7));
    char changed[sizeof text];
    for (size_t i = 0; i + 1 < sizeof text; i++) {
        memcpy(changed, text, sizeof text);
        changed[i] ^= 1;
        cr_expect_neq(h, core_hash_bytes(changed, sizeof text - 1, 7), "byte %zu ignored", i);
    }
    /* Zero-filled buffers of different lengths differ too. */
    char zeros[8] = { 0 };
    cr_expect_neq(core_hash_bytes(zeros, 4, 0), core_hash_bytes(zeros, 8, 0));
}

/* ---- errors ----------------------------------------------------------------------------- */

Test(core_error, set_fills_code_and_message_and_returns_false) {
    core_error error = { 0 };
    cr_expect_eq(error.code, CORE_ERROR_NONE, "zero is no error");
    cr_expect_not(core_error_set(&error, CORE_ERROR_IO, "cannot open %s: %s", "a.json", "No such file"));
    cr_expect_eq(error.code, CORE_ERROR_IO);
    cr_expect_str_eq(error.message, "cannot open a.json: No such file");
    /* The latest call wins, code and message together. */
    core_error_set(&error, CORE_ERROR_RANGE, "%d is over %d", 5000, 4096);
    cr_expect_eq(error.code, CORE_ERROR_RANGE);
    cr_expect_str_eq(error.message, "5000 is over 4096");
    /* NULL is allowed: the caller did not ask why. */
    cr_expect_not(core_error_set(NULL, CORE_ERROR_FORMAT, "ignored %d", 1));
}

Test(core_error, a_long_message_is_cut_and_terminated) {
    char long_name[600];
    memset(long_name, 'x', sizeof long_name - 1);
    long_name[sizeof long_name - 1] = '\0';
    core_error error;
    memset(&error, 0x55, sizeof error);
    core_error_set(&error, CORE_ERROR_IO, "cannot open %s", long_name);
    cr_expect_eq(strlen(error.message), sizeof error.message - 1);
    cr_expect(strncmp(error.message, "cannot open xxx", 15) == 0);
}

Test(core_error, every_code_has_a_name_of_its_own) {
    static const char *const expected[] = { "none", "io", "format", "version", "mismatch", "corrupt", "range",
                                            "argument" };
    cr_assert_eq(CORE_COUNTOF(expected), (size_t)CORE_ERROR_CODE_COUNT);
    for (int code = 0; code < CORE_ERROR_CODE_COUNT; code++)
        cr_expect_str_eq(core_error_code_name((core_error_code)code), expected[code], "code %d", code);
    cr_expect_str_eq(core_error_code_name(CORE_ERROR_CODE_COUNT), "unknown");
    cr_expect_str_eq(core_error_code_name((core_error_code)-1), "unknown");
}
