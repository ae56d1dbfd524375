/* bench_terrain_generate.c — generating stacks from noise, their memory, and our noise beside
 * stb_perlin.
 *
 *   terrain.generate.128, .256, .512   seconds to generate the stacks of a region of N × N
 *       columns (N/32 × N/32 chunks of seed 42's default world, from chunk (0, 0)), chunks in
 *       parallel on the job system with bench_threads() threads. Paper 002 §5 measures "N³":
 *       N × N columns of 1 m and N m of height at 1 m vertical resolution. Our stacks resolve
 *       every height from the floor up (at the 1/32 m quantum, with 1 m density samples around
 *       the surfaces and caves), so an N m window placed around the terrain's heights — this
 *       region's ground lies between about 10 and 230 m, caves reach about 110 m below it — is
 *       fully covered whatever N: the work scales with the columns, N². Targets 0.05 / 0.25 /
 *       2 s (paper 002: 33 / 256 / 2019 s).
 *   terrain.memory.512   bytes the 512 × 512-column region's stacks hold, headers included
 *       (target ≤ 3 MB; paper 002: 6.29 MB; a byte per 1 m voxel: 134 MB).
 *   noise.ours, noise.ours.scalar, noise.stb_perlin   ns per sample of a 4-octave fBm
 *       (lacunarity 2, gain 0.5) over the same 16 384 points (256 columns of 64 samples along y):
 *       ours as the column batch (terrain_noise3_column per octave) on the path the run-time
 *       dispatch chooses (terrain_noise.c: AVX-512 where the CPU has it, else AVX2, else SSE2;
 *       the run prints which, "(noise.ours: the avx512 path)" on the machine of issue 20), ours
 *       point by point (terrain_fbm3), and stb_perlin_fbm_noise3 (Debian libstb-dev), one
 *       thread each. All paths give the same bits.
 *   noise.ours.sse2, .avx2, .avx512   the column batch forced onto one path (those the CPU
 *       runs): what the dispatch gains over x86-64's baseline.
 *   noise.speedup_vs_stb   stb_perlin's time over the column batch's (noise.ours), run by run.
 */
#include "bench.h"

#include "core/core.h"
#include "jobs/jobs.h"
#include "terrain/terrain.h"
#include "terrain/terrain_internal.h"

#define STB_PERLIN_IMPLEMENTATION
#include <stb/stb_perlin.h>

#include <stdio.h>
#include <stdlib.h>

/* ---- generation ------------------------------------------------------------------------- */

typedef struct generate_bench {
    job_system *jobs;
    terrain_generation_desc params;
    int side;                             /* chunks along each side */
    terrain_stacks **stacks;
} generate_bench;

static void generate_range(void *user, size_t begin, size_t end) {
    generate_bench *b = user;
    for (size_t n = begin; n < end; n++) {
        terrain_chunk_coord c = { (int64_t)(n % (size_t)b->side), (int64_t)(n / (size_t)b->side) };
        b->stacks[n] = terrain_generate_chunk(&b->params, c);
    }
}

static size_t free_region(generate_bench *b) {
    size_t bytes = 0;
    for (int n = 0; n < b->side * b->side; n++) {
        bytes += terrain_stacks_bytes(b->stacks[n]);
        terrain_stacks_destroy(b->stacks[n]);
        b->stacks[n] = NULL;
    }
    return bytes;
}

static double sample_generate(void *user) {
    generate_bench *b = user;
    uint64_t start = core_time_ns();
    /* Batch 1: chunks differ in cost (mountains, sea), so let threads take them one by one. */
    job_parallel_for(b->jobs, (size_t)b->side * b->side, 1, generate_range, b, "terrain.generate");
    double seconds = (double)(core_time_ns() - start) * 1e-9;
    free_region(b);
    return seconds;
}

static void bench_generate(bench_context *ctx, job_system *jobs, int columns, int runs) {
    char name[64];
    snprintf(name, sizeof name, "terrain.generate.%d", columns);
    bool memory = columns == 512 && bench_wants(ctx, "terrain.memory.512");
    if (!bench_wants(ctx, name) && !memory) return;
    generate_bench b = { .jobs = jobs, .params = terrain_generation_defaults(42), .side = columns / TERRAIN_CHUNK_COLUMNS };
    b.stacks = calloc((size_t)b.side * b.side, sizeof *b.stacks);
    if (bench_wants(ctx, name)) bench_run(ctx, name, "s", runs, sample_generate, &b);
    if (memory) {
        job_parallel_for(jobs, (size_t)b.side * b.side, 1, generate_range, &b, "terrain.generate");
        double bytes = (double)free_region(&b);
        bench_record(ctx, "terrain.memory.512", "bytes", &bytes, 1);
    }
    free(b.stacks);
}

/* ---- noise -------------------------------------------------------------------------------- */

enum { NOISE_COLUMNS = 256, NOISE_COLUMN_SAMPLES = 64, NOISE_OCTAVES = 4 };
#define NOISE_SAMPLES ((double)NOISE_COLUMNS * NOISE_COLUMN_SAMPLES)

static float column_x(int c) { return (float)c * 0.731f + 0.1f; }
static float column_z(int c) { return (float)(c % 17) * 1.37f - 3.3f; }
#define COLUMN_Y0 (-2.3f)
#define COLUMN_DY 0.0625f

/* user: the terrain__noise_path to force, or NULL for the one the dispatch chooses. */
static double sample_ours_batch(void *user) {
    terrain__noise_set_path(user ? *(const terrain__noise_path *)user : TERRAIN__NOISE_AUTO);
    float sum[NOISE_COLUMN_SAMPLES], octave[NOISE_COLUMN_SAMPLES];
    double check = 0.0;
    uint64_t start = core_time_ns();
    for (int c = 0; c < NOISE_COLUMNS; c++) {
        for (int j = 0; j < NOISE_COLUMN_SAMPLES; j++) sum[j] = 0.0f;
        float frequency = 1.0f, amplitude = 1.0f;
        for (int o = 0; o < NOISE_OCTAVES; o++) {
            terrain_noise3_column(7 + (uint64_t)o, column_x(c) * frequency, COLUMN_Y0 * frequency, COLUMN_DY * frequency,
                                  column_z(c) * frequency, NOISE_COLUMN_SAMPLES, octave);
            for (int j = 0; j < NOISE_COLUMN_SAMPLES; j++) sum[j] += amplitude * octave[j];
            frequency *= 2.0f;
            amplitude *= 0.5f;
        }
        check += sum[c % NOISE_COLUMN_SAMPLES];
    }
    double ns = (double)(core_time_ns() - start) / NOISE_SAMPLES;
    terrain__noise_set_path(TERRAIN__NOISE_AUTO);
    bench_consume(check);
    return ns;
}

static double sample_ours_scalar(void *user) {
    (void)user;
    double check = 0.0;
    uint64_t start = core_time_ns();
    for (int c = 0; c < NOISE_COLUMNS; c++)
        for (int j = 0; j < NOISE_COLUMN_SAMPLES; j++)
            check += terrain_fbm3(7, column_x(c), COLUMN_Y0 + (float)j * COLUMN_DY, column_z(c), NOISE_OCTAVES);
    double ns = (double)(core_time_ns() - start) / NOISE_SAMPLES;
    bench_consume(check);
    return ns;
}

static double sample_stb(void *user) {
    (void)user;
    double check = 0.0;
    uint64_t start = core_time_ns();
    for (int c = 0; c < NOISE_COLUMNS; c++)
        for (int j = 0; j < NOISE_COLUMN_SAMPLES; j++)
            check += stb_perlin_fbm_noise3(column_x(c), COLUMN_Y0 + (float)j * COLUMN_DY, column_z(c), 2.0f, 0.5f,
                                           NOISE_OCTAVES);
    double ns = (double)(core_time_ns() - start) / NOISE_SAMPLES;
    bench_consume(check);
    return ns;
}

enum { NOISE_RUNS = 15 };

/* The column batch's paths forced one by one, beside the dispatch's choice (noise.ours). */
static const struct { terrain__noise_path path; const char *row; } NOISE_PATHS[] = {
    { TERRAIN__NOISE_SSE2, "noise.ours.sse2" },
    { TERRAIN__NOISE_AVX2, "noise.ours.avx2" },
    { TERRAIN__NOISE_AVX512, "noise.ours.avx512" },
};
enum { NOISE_PATH_ROWS = sizeof NOISE_PATHS / sizeof NOISE_PATHS[0] };

static void bench_noise(bench_context *ctx) {
    if (!bench_wants(ctx, "noise.")) return;
    /* Interleaved runs, so a disturbance on the machine hits all of them alike. */
    double ours[NOISE_RUNS], forced[NOISE_PATH_ROWS][NOISE_RUNS], scalar[NOISE_RUNS], stb[NOISE_RUNS],
        speedup[NOISE_RUNS];
    bool run_path[NOISE_PATH_ROWS];
    for (int p = 0; p < NOISE_PATH_ROWS; p++)
        run_path[p] = terrain__noise_path_supported(NOISE_PATHS[p].path) && bench_wants(ctx, NOISE_PATHS[p].row);
    bench_consume(sample_ours_batch(NULL) + sample_ours_scalar(NULL) + sample_stb(NULL));
    for (int r = 0; r < NOISE_RUNS; r++) {
        ours[r] = sample_ours_batch(NULL);
        for (int p = 0; p < NOISE_PATH_ROWS; p++)
            if (run_path[p]) forced[p][r] = sample_ours_batch((void *)&NOISE_PATHS[p].path);
        scalar[r] = sample_ours_scalar(NULL);
        stb[r] = sample_stb(NULL);
        speedup[r] = stb[r] / ours[r];
    }
    if (bench_wants(ctx, "noise.ours")) bench_record(ctx, "noise.ours", "ns", ours, NOISE_RUNS);
    for (int p = 0; p < NOISE_PATH_ROWS; p++)
        if (run_path[p]) bench_record(ctx, NOISE_PATHS[p].row, "ns", forced[p], NOISE_RUNS);
    if (bench_wants(ctx, "noise.ours.scalar")) bench_record(ctx, "noise.ours.scalar", "ns", scalar, NOISE_RUNS);
    if (bench_wants(ctx, "noise.stb_perlin")) bench_record(ctx, "noise.stb_perlin", "ns", stb, NOISE_RUNS);
    if (bench_wants(ctx, "noise.speedup_vs_stb")) bench_record(ctx, "noise.speedup_vs_stb", "x", speedup, NOISE_RUNS);
    printf("  (noise.ours: the %s path)\n", terrain__noise_path_name(terrain__noise_get_path()));
}

void bench_group_terrain_generate(bench_context *ctx) {
    if (bench_wants(ctx, "terrain.generate") || bench_wants(ctx, "terrain.memory")) {
        job_system *jobs = job_system_create(&(job_system_desc){ .threads = bench_threads(ctx) });
        bench_generate(ctx, jobs, 128, 9);
        bench_generate(ctx, jobs, 256, 5);
        bench_generate(ctx, jobs, 512, 3);
        job_system_destroy(jobs);
    }
    bench_noise(ctx);
}
