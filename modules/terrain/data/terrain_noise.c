/* terrain_noise.c — our gradient noise, its column batch, fBm, ridged and rescale-and-add
 * multifractals with domain warping (004 §2).
 *
 * Gradient noise as in Perlin's "Improving noise" (2002): the 12 cube-edge gradients (16 with
 * four repeated), quintic fade 6t⁵ − 15t⁴ + 10t³. The gradient at a lattice point comes from a
 * 32-bit hash of (seed, X, Y, Z) — no permutation table, so there is no period of 256 and no
 * shared state; every octave and every field gets its own seed.
 *
 * Why SIMD, and why it may not change a bit: generation takes all its noise from these batches
 * (the 3D column, the 2D row, the multifractal's row), and the world's determinism is a
 * promise: a chunk's bytes depend on (params, coordinate) only, never on the CPU that generated
 * it or on the thread count. So the batches run on explicit SIMD paths chosen once at run time
 * (terrain__noise_set_path in terrain_internal.h): SSE2, x86-64's baseline (8 lanes in pairs
 * of registers); AVX2, 8 lanes; AVX-512, 16 lanes (the widest the CPU has wins); off x86-64
 * the portable C blocks below. The default build stays portable x86-64 (no -march): the wider
 * paths are functions compiled with target attributes, reached only after
 * __builtin_cpu_supports. All paths are one body (terrain_noise_lanes.h, GCC/Clang vector
 * extensions) whose every float operation is the scalar code's, in the same order, lane by
 * lane, with no FMA contraction ("fma" is never a target; -std=c11 keeps GCC from contracting,
 * a pragma keeps Clang): each lane equals terrain__noise3 / noise2_raw /
 * terrain__multifractal2 bit for bit, which test_terrain_noise.c checks on every path the CPU
 * runs.
 *
 * What is hoisted: the x/z part of a column's hash (once per column, as before); on AVX2 and
 * AVX-512 also the y part and the choice of gradient, once per lattice level and corner
 * column rather than once per point and corner, read back with lane permutes (the tables in
 * terrain_noise_lanes.h). The portable blocks are the earlier form: fixed NOISE_BLOCK loops
 * with selects instead of branches, which GCC's -O2 vectorises with SSE2 on its own.
 *
 * The scattered-point batch (terrain__noise3_points: the perturbed cave map's lookups, each point
 * in a cell of its own, so nothing is hoisted) is such a block, compiled twice: as is, and with
 * target("avx2") for 8 lanes where the dispatch picked AVX2 or AVX-512. The same C either way,
 * no FMA, so the bits are the scalar terrain__noise3_cell's (test_terrain_generate_shape.c checks).
 */
#include "terrain/data/terrain_data_internal.h"

#include "core/core.h"

#include <math.h>
#include <stdatomic.h>
#include <string.h>

#define NOISE_BLOCK 8

/* Scales the raw sums into [-1, 1]. Over 2·10⁷ random points the 12-gradient 3D noise stays
 * within ±0.9995 (standard deviation 0.27); rare lattice configurations can exceed 1 by a few
 * per cent, which the clamp catches. */
#define NOISE3_SCALE 1.0f
/* 2D gradients (±1, ±2) and (±2, ±1): raw values measured within ±1.52. */
#define NOISE2_SCALE 0.65f

/* Multipliers that spread lattice coordinates over the hash input (odd, high entropy). */
#define HASH_X 0x8da6b343u
#define HASH_Y 0xd8163841u
#define HASH_Z 0xcb1ab31fu

/* Hashing a lattice point: the x and z parts go through the full finaliser (once per column
 * in the batch), the y part through one multiply round per sample. A χ² test of the gradient
 * indices of neighbouring lattice points (10⁶ pairs along each axis) scores like a 64-bit
 * splitmix hash of (X, Y, Z); XOR-ing three products into one full finaliser scored worse. */
static inline __attribute__((always_inline)) uint32_t mix32(uint32_t h) {
    /* "lowbias32": two multiply–xorshift rounds. */
    h ^= h >> 16;
    h *= 0x7feb352du;
    h ^= h >> 15;
    h *= 0x846ca68bu;
    h ^= h >> 16;
    return h;
}

static inline __attribute__((always_inline)) uint32_t mix32_y(uint32_t column_hash, uint32_t yi) {
    uint32_t h = column_hash ^ (yi * HASH_Y);
    h ^= h >> 15;
    h *= 0x2c1b3c6du;
    h ^= h >> 12;
    return h;
}

/* Lattice indices are read modulo 2^32 (the hash multiplies them as uint32_t), so cells are
 * passed as uint32_t and added with wrap-around: cell + offset's floor names the same lattice
 * point whichever way a coordinate was split. */
static inline __attribute__((always_inline)) uint32_t hash_x(uint32_t seed, uint32_t xi) {
    return mix32(seed ^ (xi * HASH_X));
}
static inline __attribute__((always_inline)) uint32_t hash_xz(uint32_t x_hash, uint32_t zi) {
    return mix32(x_hash ^ (zi * HASH_Z));
}

uint32_t terrain__seed32(uint64_t seed) {
    uint64_t h = core_hash_u64(seed ^ 0x6e6f697365ull);   /* "noise" */
    return (uint32_t)(h ^ (h >> 32));
}

/* The cell of a floored double, modulo 2^32 as the hash reads it: exact while |v| < 2^53. */
static inline uint32_t lattice_cell(double floored) {
    return (uint32_t)(uint64_t)(int64_t)floored;
}

terrain__lattice terrain__lattice_split(double v) {
    /* Why the split: far out, v itself as a float has a coarse ulp (0.06 cells at 10⁶ cells),
     * which would quantise the noise into steps; v − ⌊v⌋ taken in double is exact, and as a
     * float it keeps 2⁻²⁴ of a cell wherever the cell lies. */
    double floored = floor(v);
    return (terrain__lattice){ lattice_cell(floored), (float)(v - floored) };
}

static inline __attribute__((always_inline)) int floor_to_int(float v) {
    int t = (int)v;                                 /* truncates towards zero */
    return t - (v < (float)t);                      /* one less for negative non-integers */
}

static inline __attribute__((always_inline)) float fade(float t) {
    return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f);
}

static inline float lerp(float a, float b, float t) {
    return a + t * (b - a);
}

/* Branch-free selection and negation on the float's bits: the hash bits are random, so branches
 * would be mispredicted half the time (scalar code), and selects keep the vector loop simple. */
static inline __attribute__((always_inline)) uint32_t float_bits(float f) {
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}
static inline __attribute__((always_inline)) float bits_float(uint32_t u) {
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}
/* mask all ones → b, all zeros → a. */
static inline __attribute__((always_inline)) uint32_t select_bits(uint32_t mask, uint32_t a, uint32_t b) {
    return (a & ~mask) | (b & mask);
}

/* Dot product of the gradient picked by the hash's top 4 bits with (x, y, z) (Perlin 2002):
 *     u = g < 8 ? x : y;   v = g < 4 ? y : (g == 12 || g == 14 ? x : z);
 *     return (g & 1 ? −u : u) + (g & 2 ? −v : v);                                          */
static inline __attribute__((always_inline)) float grad3(uint32_t h, float x, float y, float z) {
    uint32_t g = h >> 28;
    uint32_t xb = float_bits(x), yb = float_bits(y), zb = float_bits(z);
    uint32_t u = select_bits(0u - (uint32_t)(g >= 8), xb, yb);
    uint32_t v = select_bits(0u - (uint32_t)(g == 12 || g == 14), zb, xb);
    v = select_bits(0u - (uint32_t)(g < 4), v, yb);
    u ^= (g & 1u) << 31;
    v ^= (g & 2u) << 30;
    return bits_float(u) + bits_float(v);
}

/* 2D: gradients (±1, ±2) and (±2, ±1) by the hash's top 3 bits. */
static inline __attribute__((always_inline)) float grad2(uint32_t h, float x, float z) {
    uint32_t g = h >> 29;
    uint32_t swap = 0u - (g >> 2);
    uint32_t u = select_bits(swap, float_bits(x), float_bits(z));
    uint32_t v = select_bits(swap, float_bits(z), float_bits(x));
    u ^= (g & 1u) << 31;
    v ^= (g & 2u) << 30;
    return bits_float(u) + 2.0f * bits_float(v);
}

/* The x/z part of one cell, shared by every point of a column. */
typedef struct column_cell {
    uint32_t h00, h10, h01, h11;                    /* seed ^ X-part ^ Z-part of the four corners */
    float fx, fz, u, w;                             /* offsets in the cell and their fades */
} column_cell;

/* x and z in double, split into cell and offset once per column (terrain__lattice_split): for a
 * float argument the offset is x − ⌊x⌋ exactly, as the float form computed it. */
static inline column_cell cell_xz(uint32_t seed, double x, double z) {
    terrain__lattice sx = terrain__lattice_split(x), sz = terrain__lattice_split(z);
    column_cell c;
    uint32_t hx0 = hash_x(seed, sx.cell), hx1 = hash_x(seed, sx.cell + 1u);
    c.h00 = hash_xz(hx0, sz.cell);
    c.h10 = hash_xz(hx1, sz.cell);
    c.h01 = hash_xz(hx0, sz.cell + 1u);
    c.h11 = hash_xz(hx1, sz.cell + 1u);
    c.fx = sx.offset;
    c.fz = sz.offset;
    c.u = fade(c.fx);
    c.w = fade(c.fz);
    return c;
}

/* The noise at height y inside the column cell c: the body of the vectorised loop. Forced
 * inline: -O2 would otherwise keep it a call, and a call in the loop stops vectorisation. */
static inline __attribute__((always_inline)) float noise3_in_column(const column_cell *c, float y) {
    int yi = floor_to_int(y);
    float fy = y - (float)yi;
    float fx = c->fx, fz = c->fz, fx1 = fx - 1.0f, fy1 = fy - 1.0f, fz1 = fz - 1.0f;
    uint32_t y0 = (uint32_t)yi, y1 = y0 + 1u;
    float n000 = grad3(mix32_y(c->h00, y0), fx, fy, fz);
    float n100 = grad3(mix32_y(c->h10, y0), fx1, fy, fz);
    float n010 = grad3(mix32_y(c->h00, y1), fx, fy1, fz);
    float n110 = grad3(mix32_y(c->h10, y1), fx1, fy1, fz);
    float n001 = grad3(mix32_y(c->h01, y0), fx, fy, fz1);
    float n101 = grad3(mix32_y(c->h11, y0), fx1, fy, fz1);
    float n011 = grad3(mix32_y(c->h01, y1), fx, fy1, fz1);
    float n111 = grad3(mix32_y(c->h11, y1), fx1, fy1, fz1);
    float v = fade(fy);
    float x00 = lerp(n000, n100, c->u), x10 = lerp(n010, n110, c->u);
    float x01 = lerp(n001, n101, c->u), x11 = lerp(n011, n111, c->u);
    float n = lerp(lerp(x00, x10, v), lerp(x01, x11, v), c->w) * NOISE3_SCALE;
    n = n > 1.0f ? 1.0f : n;
    return n < -1.0f ? -1.0f : n;
}

float terrain__noise3(uint32_t seed, double x, float y, double z) {
    column_cell c = cell_xz(seed, x, z);
    return noise3_in_column(&c, y);
}

/* NOISE_BLOCK points: a loop of constant trip count, which -O2 vectorises. The cell is copied
 * to a local so that its fields are loop invariants (through a pointer they might alias out). */
static void noise3_block(column_cell cell, float y0, float dy, int first, float *restrict out) {
    for (int j = 0; j < NOISE_BLOCK; j++) out[j] = noise3_in_column(&cell, y0 + (float)(first + j) * dy);
}

/* The portable path: blocks of NOISE_BLOCK points, as the compiler vectorises them. */
static void noise3_column_portable(const column_cell *c, float y0, float dy, int count, float *out) {
    int j = 0;
    for (; j + NOISE_BLOCK <= count; j += NOISE_BLOCK) noise3_block(*c, y0, dy, j, out + j);
    if (j < count) {
        float tail[NOISE_BLOCK];
        noise3_block(*c, y0, dy, j, tail);
        for (int t = 0; j + t < count; t++) out[j + t] = tail[t];
    }
}

/* Unclamped (raw values stay within ±0.99 after scaling; the multifractal, which normalises its
 * sum anyway, uses this form: a clamp is a branch its vectorised loop cannot take). The point
 * is (cell_x + x, cell_z + z): x and z are offsets from a cell, of any sign or size, whose
 * floors move the cell (terrain__lattice_split says why). */
static inline __attribute__((always_inline)) float noise2_raw(uint32_t seed, uint32_t cell_x, uint32_t cell_z, float x,
                                                              float z) {
    int xi = floor_to_int(x), zi = floor_to_int(z);
    float fx = x - (float)xi, fz = z - (float)zi;
    uint32_t cx = cell_x + (uint32_t)xi, cz = cell_z + (uint32_t)zi;
    uint32_t hx0 = hash_x(seed, cx), hx1 = hash_x(seed, cx + 1u);
    /* The same one-round mix for the last coordinate as the 3D batch uses for y. */
    float n00 = grad2(mix32_y(hx0, cz), fx, fz);
    float n10 = grad2(mix32_y(hx1, cz), fx - 1.0f, fz);
    float n01 = grad2(mix32_y(hx0, cz + 1u), fx, fz - 1.0f);
    float n11 = grad2(mix32_y(hx1, cz + 1u), fx - 1.0f, fz - 1.0f);
    float u = fade(fx), w = fade(fz);
    return lerp(lerp(n00, n10, u), lerp(n01, n11, u), w) * NOISE2_SCALE;
}

float terrain__noise2_cell(uint32_t seed, uint32_t cell_x, float x, uint32_t cell_z, float z) {
    float n = noise2_raw(seed, cell_x, cell_z, x, z);
    n = n > 1.0f ? 1.0f : n;
    return n < -1.0f ? -1.0f : n;
}

#define NOISE2_BLOCK 8

float terrain__noise2(uint32_t seed, float x, float z) {
    return terrain__noise2_cell(seed, 0, x, 0, z);
}

/* A row's origin and z, split once (terrain__noise2_row). */
typedef struct noise2_origin {
    uint32_t cell_x, cell_z;
    float offset_x, offset_z;
} noise2_origin;

static noise2_origin noise2_origin_make(double x0, double z) {
    terrain__lattice sx = terrain__lattice_split(x0), sz = terrain__lattice_split(z);
    return (noise2_origin){ sx.cell, sz.cell, sx.offset, sz.offset };
}

static void noise2_block(uint32_t seed, noise2_origin o, const float *restrict dxs, float scale, float *restrict out) {
    for (int j = 0; j < NOISE2_BLOCK; j++)
        out[j] = noise2_raw(seed, o.cell_x, o.cell_z, o.offset_x + dxs[j] * scale, o.offset_z);
}

static void noise2_row_portable(uint32_t seed, noise2_origin o, const float *dxs, float scale, int count, float *out) {
    int j = 0;
    for (; j + NOISE2_BLOCK <= count; j += NOISE2_BLOCK) noise2_block(seed, o, dxs + j, scale, out + j);
    if (j < count) {
        float x_tail[NOISE2_BLOCK], tail[NOISE2_BLOCK];
        for (int t = 0; t < NOISE2_BLOCK; t++) x_tail[t] = dxs[j + (j + t < count ? t : 0)];
        noise2_block(seed, o, x_tail, scale, tail);
        for (int t = 0; j + t < count; t++) out[j + t] = tail[t];
    }
}

/* ---- public forms ----------------------------------------------------------------------- */

float terrain_noise3(uint64_t seed, float x, float y, float z) {
    return terrain__noise3(terrain__seed32(seed), x, y, z);
}

void terrain_noise3_column(uint64_t seed, float x, float y0, float dy, float z, int count, float *out) {
    terrain__noise3_column(terrain__seed32(seed), (double)x, y0, dy, (double)z, count, out);
}

/* Octave k's seed: a different lattice per octave, so octaves do not all vanish together at
 * the origin's lattice points as they do with one shared permutation. */
static inline uint32_t octave_seed(uint32_t seed, int octave) {
    return mix32(seed + (uint32_t)octave * 0x9e3779b9u);
}

float terrain_fbm3(uint64_t seed, float x, float y, float z, int octaves) {
    /* Lacunarity 2, gain 0.5, amplitudes not renormalised: the same sum as
     * stb_perlin_fbm_noise3(x, y, z, 2, 0.5, octaves). */
    uint32_t s = terrain__seed32(seed);
    float sum = 0.0f, amplitude = 1.0f, frequency = 1.0f;
    for (int k = 0; k < octaves; k++) {
        sum += amplitude * terrain__noise3(octave_seed(s, k), (double)(x * frequency), y * frequency,
                                           (double)(z * frequency));
        amplitude *= 0.5f;
        frequency *= 2.0f;
    }
    return sum;
}

/* ---- ridged multifractal ---------------------------------------------------------------- */

float terrain__ridged3(uint32_t seed, float x, float y, float z, int octaves, float gain) {
    float n[16];
    if (octaves > 16) octaves = 16;
    float frequency = 1.0f;
    for (int k = 0; k < octaves; k++, frequency *= 2.0f)
        n[k] = terrain__noise3(octave_seed(seed, k), (double)(x * frequency), y * frequency, (double)(z * frequency));
    return terrain__ridged_from_octaves(n, octaves, gain);
}

/* ---- rescale-and-add multifractal with domain warping (004 §2) --------------------------- */

float terrain__multifractal_octaves(float lacunarity, float hurst, float spacing, int max_octaves) {
    /* 004 §4: ν = log σ / log r^−H, i.e. the octave whose amplitude r^−νH has shrunk to the
     * sampling spacing σ (σ measured in units of the first octave's amplitude). */
    float octaves = logf(spacing) / (-hurst * logf(lacunarity));
    if (!(octaves >= 1.0f)) octaves = 1.0f;
    if (octaves > (float)max_octaves) octaves = (float)max_octaves;
    return octaves;
}

/* 004 §2.2's control vectors, as published (Figure 3); the minus sign of e2's first component
 * is lost in our text copy ("( 0:07,0:13)") and restored here. */
static const float WARP_E1[2] = { 0.35f, 0.16f };
static const float WARP_E2[2] = { -0.07f, 0.13f };
static const float WARP_E3[2] = { 0.11f, 0.17f };

/* B_k: rotation by k golden angles (2.39996 rad), k = 0 … 16, as (cos, sin). */
static const float OCTAVE_ROTATION[17][2] = {
    { 1.000000000f, 0.000000000f },
    { -0.737368878f, 0.675490294f },
    { 0.087425725f, -0.996171041f },
    { 0.608438860f, 0.793600752f },
    { -0.984713485f, -0.174181951f },
    { 0.843755296f, -0.536728051f },
    { -0.259604306f, 0.965715074f },
    { -0.460907023f, -0.887448430f },
    { 0.939321296f, 0.343038633f },
    { -0.924345557f, 0.381556406f },
    { 0.423845998f, -0.905734271f },
    { 0.299283862f, 0.954164121f },
    { -0.865211208f, -0.501407584f },
    { 0.976675774f, -0.214719426f },
    { -0.575129432f, 0.818062428f },
    { -0.128510686f, -0.991708124f },
    { 0.764648993f, 0.644446986f }
};

/* What one octave of the multifractal shares across points. The row's origin (x0, z), turned
 * and scaled into the octave's lattice in double and split there (cell, offset), so that the
 * points' own float parts are only their small distances dx from it (mf_place). */
typedef struct mf_octave {
    uint32_t seed;
    float cos_b, sin_b, frequency, amplitude, r0, warp;
    uint32_t cell_x, cell_z;
    float offset_x, offset_z;
} mf_octave;

/* 1/√v for v > 0 without sqrtf (which, under C's errno rules, is a call the vectoriser must
 * keep): the classic bit estimate and two Newton steps, relative error below 5·10⁻⁶. */
static inline __attribute__((always_inline)) float inverse_sqrt(float v) {
    float r = bits_float(0x5f3759dfu - (float_bits(v) >> 1));
    r = r * (1.5f - 0.5f * v * r * r);
    return r * (1.5f - 0.5f * v * r * r);
}

/* One octave at one point; the point's warp state (height so far, rotation ρ, translation t)
 * is updated in place. The row form runs this over a block of points, so it vectorises. */
static inline __attribute__((always_inline)) void mf_step(const mf_octave *o, float dx, float *sum, float *rho_x,
                                                          float *rho_z, float *t_x, float *t_z) {
    float wx = (*rho_x * *t_x - *rho_z * *t_z) * o->warp;
    float wz = (*rho_z * *t_x + *rho_x * *t_z) * o->warp;
    /* B·(x0 + dx, z) + warp, scaled: the origin's part is in the cell and offset (mf_place). */
    float px = o->offset_x + (o->cos_b * dx + wx) * o->frequency;
    float pz = o->offset_z + (o->sin_b * dx + wz) * o->frequency;
    float h = *sum + o->amplitude * noise2_raw(o->seed, o->cell_x, o->cell_z, px, pz);
    float roughness = o->r0 - h;
    float rx = *rho_x + WARP_E1[0] * roughness + WARP_E2[0];
    float rz = *rho_z + WARP_E1[1] * roughness + WARP_E2[1];
    float length2 = rx * rx + rz * rz;
    float inverse = inverse_sqrt(length2 + 1e-12f);      /* no branch: 0 cannot reach it */
    *rho_x = rx * inverse;
    *rho_z = rz * inverse;
    *t_x = WARP_E3[0] * h;
    *t_z = WARP_E3[1] * roughness;
    *sum = h;
}

/* The octaves' shared parameters; returns how many there are and the sum of their weights. */
static int mf_octaves(const terrain__multifractal *mf, mf_octave *octaves, float *total) {
    float r = mf->lacunarity, r0 = powf(r, -mf->hurst);
    int full = (int)mf->octaves;
    if (full > 16) full = 16;
    float fraction = mf->octaves - (float)full;
    float amplitude = 1.0f, frequency = 1.0f;
    int count = 0;
    *total = 0.0f;
    for (int k = 0; k <= full; k++) {
        float weight = k < full ? 1.0f : fraction;
        if (weight <= 0.0f) break;
        octaves[count++] = (mf_octave){ octave_seed(mf->seed, k), OCTAVE_ROTATION[k][0], OCTAVE_ROTATION[k][1],
                                        frequency, weight * amplitude, r0, mf->warp, 0, 0, 0.0f, 0.0f };
        *total += weight * amplitude;
        amplitude *= r0;
        frequency *= r;
    }
    return count;
}

/* Each octave's image of the row's origin (x0, z): B_k·(x0, z)·r^k in double, then split. */
static void mf_place(mf_octave *octaves, int count, double x0, double z) {
    for (int k = 0; k < count; k++) {
        mf_octave *o = &octaves[k];
        double c = o->cos_b, s = o->sin_b, f = o->frequency;
        terrain__lattice px = terrain__lattice_split((c * x0 - s * z) * f), pz = terrain__lattice_split((s * x0 + c * z) * f);
        o->cell_x = px.cell;
        o->cell_z = pz.cell;
        o->offset_x = px.offset;
        o->offset_z = pz.offset;
    }
}

float terrain__multifractal2(const terrain__multifractal *mf, double x0, float dx, double z) {
    /* Equation (1): H(x) = Σ_k r^(−kH) S(r^k x), k = 0 … ν, the last octave weighted by frac(ν).
     *
     * Domain warping (§2.2), our reading of the scrambled formulas:
     *   R_i = R_0 − H_i with R_0 = r^−H           (roughness falls with height; the "−" and the
     *                                              exponent's sign are lost in our copy)
     *   ρ_{i+1} = normalise(ρ_i + e1·R_i + e2)     (the rotation vector, ρ_0 = (1, 0))
     *   t_{i+1} = e3 ∘ (H_i, R_i)                  (translation: e3 weighs height and roughness
     *                                              component-wise; the text shows a column
     *                                              vector (H_i, R_i) after e3)
     * H_i is the sum after octave i in units of the first octave's amplitude. Equation (2)
     * rotates the whole domain about the origin; on an infinite domain that makes the warp grow
     * with the distance from the origin (a change dρ moves a point by |x|·dρ), so we rotate the
     * translation instead: octave i samples S(r^i·(B_i x + ρ_i ⊗ t_i)), where B_i is a fixed
     * rotation per octave (it keeps the octaves' lattices from lining up) and ρ_i ⊗ t_i is t_i
     * turned by ρ_i. The warp stays a bounded, continuous offset of about 0.2 wavelengths,
     * which turns with roughness as the paper's figure shows. */
    mf_octave octaves[17];
    float total;
    int count = mf_octaves(mf, octaves, &total);
    mf_place(octaves, count, x0, z);
    float sum = 0.0f, rho_x = 1.0f, rho_z = 0.0f, t_x = 0.0f, t_z = 0.0f;
    for (int k = 0; k < count; k++) mf_step(&octaves[k], dx, &sum, &rho_x, &rho_z, &t_x, &t_z);
    return sum * (total > 0.0f ? 1.0f / total : 0.0f);   /* as the row form computes it */
}

#define MF_BLOCK 8

/* MF_BLOCK points at once: each loop over the block has a constant trip count (vectorised). */
static void mf_block(const mf_octave *octaves, int count, float total, const float *restrict dxs,
                     float *restrict out) {
    float sum[MF_BLOCK], rho_x[MF_BLOCK], rho_z[MF_BLOCK], t_x[MF_BLOCK], t_z[MF_BLOCK];
    for (int j = 0; j < MF_BLOCK; j++) {
        sum[j] = 0.0f;
        rho_x[j] = 1.0f;
        rho_z[j] = 0.0f;
        t_x[j] = 0.0f;
        t_z[j] = 0.0f;
    }
    for (int k = 0; k < count; k++) {
        mf_octave o = octaves[k];
        for (int j = 0; j < MF_BLOCK; j++) mf_step(&o, dxs[j], &sum[j], &rho_x[j], &rho_z[j], &t_x[j], &t_z[j]);
    }
    float inverse_total = total > 0.0f ? 1.0f / total : 0.0f;
    for (int j = 0; j < MF_BLOCK; j++) out[j] = sum[j] * inverse_total;
}

static void multifractal2_row_portable(const mf_octave *octaves, int octave_count, float total, const float *dxs,
                                       int count, float *out) {
    int j = 0;
    for (; j + MF_BLOCK <= count; j += MF_BLOCK) mf_block(octaves, octave_count, total, dxs + j, out + j);
    if (j < count) {
        float x_tail[MF_BLOCK], tail[MF_BLOCK];
        for (int t = 0; t < MF_BLOCK; t++) x_tail[t] = dxs[j + (j + t < count ? t : 0)];
        mf_block(octaves, octave_count, total, x_tail, tail);
        for (int t = 0; j + t < count; t++) out[j + t] = tail[t];
    }
}

/* ---- explicit SIMD paths and their dispatch (x86-64) ------------------------------------- */

#if defined(__x86_64__)
#include <immintrin.h>
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF            /* GCC's -std=c11 already keeps a·b + c two operations */
#endif
typedef float noise_vf8 __attribute__((vector_size(32)));
typedef int32_t noise_vi8 __attribute__((vector_size(32)));
typedef uint32_t noise_vu8 __attribute__((vector_size(32)));
typedef float noise_vf16 __attribute__((vector_size(64)));
typedef int32_t noise_vi16 __attribute__((vector_size(64)));
typedef uint32_t noise_vu16 __attribute__((vector_size(64)));

/* SSE2 runs 8 lanes as pairs of 4-lane registers: two independent chains per step hide the
 * latency of SSE2's long 32-bit multiply (four instructions; pmulld is SSE4.1), which made one
 * 4-lane chain 18 % slower than the portable blocks. GCC and Clang warn that 32-byte vectors
 * change the ABI without AVX; it does not matter here, where every such function is inlined
 * (GCC warns at the end of the file, so the warning is off from here on). */
#pragma GCC diagnostic ignored "-Wpsabi"
#define LANES 8
#define SUFFIX sse2
#define TARGET
#define NOISE_ISA_SSE2
#include "terrain_noise_lanes.h"
#undef NOISE_ISA_SSE2
#undef LANES
#undef SUFFIX
#undef TARGET

#define LANES 8
#define SUFFIX avx2
#define TARGET __attribute__((target("avx2")))
#define NOISE_ISA_AVX2
#include "terrain_noise_lanes.h"
#undef NOISE_ISA_AVX2
#undef LANES
#undef SUFFIX
#undef TARGET

#define LANES 16
#define SUFFIX avx512
#define TARGET __attribute__((target("avx512f")))
#define NOISE_ISA_AVX512
#include "terrain_noise_lanes.h"
#undef NOISE_ISA_AVX512
#undef LANES
#undef SUFFIX
#undef TARGET
#endif

bool terrain__noise_path_supported(terrain__noise_path path) {
    switch (path) {
    case TERRAIN__NOISE_AUTO:
    case TERRAIN__NOISE_PORTABLE: return true;
#if defined(__x86_64__)
    case TERRAIN__NOISE_SSE2: return true;
    case TERRAIN__NOISE_AVX2: __builtin_cpu_init(); return __builtin_cpu_supports("avx2");
    case TERRAIN__NOISE_AVX512: __builtin_cpu_init(); return __builtin_cpu_supports("avx512f");
#endif
    default: return false;
    }
}

const char *terrain__noise_path_name(terrain__noise_path path) {
    static const char *const names[TERRAIN__NOISE_PATH_COUNT] = { "auto", "portable", "sse2", "avx2", "avx512" };
    return path >= 0 && path < TERRAIN__NOISE_PATH_COUNT ? names[path] : "unknown";
}

/* The widest path the CPU has: each is faster than the narrower ones on the machines measured
 * (noise.ours.* rows of tools/bench). */
static terrain__noise_path noise_best_path(void) {
    if (terrain__noise_path_supported(TERRAIN__NOISE_AVX512)) return TERRAIN__NOISE_AVX512;
    if (terrain__noise_path_supported(TERRAIN__NOISE_AVX2)) return TERRAIN__NOISE_AVX2;
    if (terrain__noise_path_supported(TERRAIN__NOISE_SSE2)) return TERRAIN__NOISE_SSE2;
    return TERRAIN__NOISE_PORTABLE;
}

/* 0 (TERRAIN__NOISE_AUTO) until the first batch chooses; every path gives the same bits, so
 * threads that race to choose, or a test that switches paths, change only the speed. */
static _Atomic int noise_path = TERRAIN__NOISE_AUTO;

static inline terrain__noise_path noise_current_path(void) {
    int path = atomic_load_explicit(&noise_path, memory_order_relaxed);
    if (path == TERRAIN__NOISE_AUTO) {
        path = noise_best_path();
        atomic_store_explicit(&noise_path, path, memory_order_relaxed);
    }
    return (terrain__noise_path)path;
}

bool terrain__noise_set_path(terrain__noise_path path) {
    if (!terrain__noise_path_supported(path)) return false;
    atomic_store_explicit(&noise_path, path == TERRAIN__NOISE_AUTO ? noise_best_path() : path, memory_order_relaxed);
    return true;
}

terrain__noise_path terrain__noise_get_path(void) {
    return noise_current_path();
}

void terrain__noise3_column(uint32_t seed, double x, float y0, float dy, double z, int count, float *out) {
    column_cell c = cell_xz(seed, x, z);
    switch (noise_current_path()) {
#if defined(__x86_64__)
    case TERRAIN__NOISE_SSE2: noise3_column_sse2(&c, y0, dy, count, out); return;
    case TERRAIN__NOISE_AVX2: noise3_column_avx2(&c, y0, dy, count, out); return;
    case TERRAIN__NOISE_AVX512: noise3_column_avx512(&c, y0, dy, count, out); return;
#endif
    default: noise3_column_portable(&c, y0, dy, count, out); return;
    }
}

void terrain__noise2_row(uint32_t seed, double x0, const float *dxs, float scale, double z, int count, float *out) {
    noise2_origin o = noise2_origin_make(x0, z);
    switch (noise_current_path()) {
#if defined(__x86_64__)
    case TERRAIN__NOISE_SSE2: noise2_row_sse2(seed, &o, dxs, scale, count, out); return;
    case TERRAIN__NOISE_AVX2: noise2_row_avx2(seed, &o, dxs, scale, count, out); return;
    case TERRAIN__NOISE_AVX512: noise2_row_avx512(seed, &o, dxs, scale, count, out); return;
#endif
    default: noise2_row_portable(seed, o, dxs, scale, count, out); return;
    }
}

void terrain__multifractal2_row(const terrain__multifractal *mf, double x0, const float *dxs, double z, int count,
                                float *out) {
    mf_octave octaves[17];
    float total;
    int octave_count = mf_octaves(mf, octaves, &total);
    mf_place(octaves, octave_count, x0, z);
    switch (noise_current_path()) {
#if defined(__x86_64__)
    case TERRAIN__NOISE_SSE2: multifractal2_row_sse2(octaves, octave_count, total, dxs, count, out); return;
    case TERRAIN__NOISE_AVX2: multifractal2_row_avx2(octaves, octave_count, total, dxs, count, out); return;
    case TERRAIN__NOISE_AVX512: multifractal2_row_avx512(octaves, octave_count, total, dxs, count, out); return;
#endif
    default: multifractal2_row_portable(octaves, octave_count, total, dxs, count, out); return;
    }
}

/* ---- scattered points: the perturbed cave map (002 §3.1.3.2, Fig. 11) ---------------------- */

/* NOISE_BLOCK points, each with its own cell: the loop has a constant trip count and no branch
 * (cell_xz and noise3_in_column are selects and arithmetic), so -O2 vectorises it; every lane is
 * terrain__noise3's scalar code, so the bits are the same on any CPU. */
/* The point (cell_x + x, y, cell_z + z), x and z float offsets from the cells: cell_xz's body with
 * the floors of the offsets added to the cells, spelt out (a call would stop the vectoriser). */
static inline __attribute__((always_inline)) float noise3_at_cell(uint32_t seed, uint32_t cell_x, float x, float y,
                                                                  uint32_t cell_z, float z) {
    int xi = floor_to_int(x), zi = floor_to_int(z);
    uint32_t cx = cell_x + (uint32_t)xi, cz = cell_z + (uint32_t)zi;
    uint32_t hx0 = hash_x(seed, cx), hx1 = hash_x(seed, cx + 1u);
    column_cell c;
    c.h00 = hash_xz(hx0, cz);
    c.h10 = hash_xz(hx1, cz);
    c.h01 = hash_xz(hx0, cz + 1u);
    c.h11 = hash_xz(hx1, cz + 1u);
    c.fx = x - (float)xi;
    c.fz = z - (float)zi;
    c.u = fade(c.fx);
    c.w = fade(c.fz);
    return noise3_in_column(&c, y);
}

float terrain__noise3_cell(uint32_t seed, uint32_t cell_x, float x, float y, uint32_t cell_z, float z) {
    return noise3_at_cell(seed, cell_x, x, y, cell_z, z);
}

static inline __attribute__((always_inline)) void noise3_points_body(uint32_t seed, noise2_origin o,
                                                                    const float *restrict dxs,
                                                                    const float *restrict ys,
                                                                    const float *restrict dzs, float *restrict out) {
    for (int j = 0; j < NOISE_BLOCK; j++)
        out[j] = noise3_at_cell(seed, o.cell_x, o.offset_x + dxs[j], ys[j], o.cell_z, o.offset_z + dzs[j]);
}

static void noise3_points_block(uint32_t seed, noise2_origin o, const float *restrict dxs, const float *restrict ys,
                                const float *restrict dzs, float *restrict out) {
    noise3_points_body(seed, o, dxs, ys, dzs, out);
}

#if defined(__x86_64__)
/* The same body with AVX2's 8 lanes (no FMA: "fma" is not a target, so the bits are the same). */
__attribute__((target("avx2"))) static void noise3_points_block_avx2(uint32_t seed, noise2_origin o,
                                                                     const float *restrict dxs,
                                                                     const float *restrict ys,
                                                                     const float *restrict dzs, float *restrict out) {
    noise3_points_body(seed, o, dxs, ys, dzs, out);
}
#endif

void terrain__noise3_points(uint32_t seed, double x0, double z0, const float *dxs, const float *ys, const float *dzs,
                            int count, float *out) {
    void (*block)(uint32_t, noise2_origin, const float *restrict, const float *restrict, const float *restrict,
                  float *restrict) = noise3_points_block;
#if defined(__x86_64__)
    terrain__noise_path path = noise_current_path();
    if (path == TERRAIN__NOISE_AVX2 || path == TERRAIN__NOISE_AVX512) block = noise3_points_block_avx2;
#endif
    noise2_origin o = noise2_origin_make(x0, z0);
    int j = 0;
    for (; j + NOISE_BLOCK <= count; j += NOISE_BLOCK) block(seed, o, dxs + j, ys + j, dzs + j, out + j);
    if (j < count) {
        float x[NOISE_BLOCK], y[NOISE_BLOCK], z[NOISE_BLOCK], tail[NOISE_BLOCK];
        for (int t = 0; t < NOISE_BLOCK; t++) {
            int from = j + t < count ? j + t : j;
            x[t] = dxs[from], y[t] = ys[from], z[t] = dzs[from];
        }
        block(seed, o, x, y, z, tail);
        for (int t = 0; j + t < count; t++) out[j + t] = tail[t];
    }
}
