/* core_lanes.h — four 32-bit lanes, two doubles, or sixteen bytes, in GCC's vector types.
 *
 * For the loops GCC does not vectorise at -O2 (a trip count it does not know, several arrays):
 * SSE2 on any x86-64, NEON on ARM, no runtime dispatch. Each lane does the same operations in the
 * same order as the scalar loop it replaces, so the results are the same bits (no FMA contraction
 * on the portable target). Loads and stores go through memcpy: no alignment is assumed.
 *
 *     core_floats4 x = core_floats4_load(p);
 *     core_ints4 big = x > core_floats4_splat(1.0f);          // comparisons give −1 or 0 a lane
 *     core_floats4_store(p, core_floats4_select(big, core_floats4_splat(1.0f), x));
 */
#ifndef CORE_LANES_H
#define CORE_LANES_H

#include <stdint.h>
#include <string.h>

typedef float core_floats4 __attribute__((vector_size(16)));
typedef int32_t core_ints4 __attribute__((vector_size(16)));
typedef uint8_t core_bytes16 __attribute__((vector_size(16)));
typedef double core_doubles2 __attribute__((vector_size(16)));
typedef float core_floats2 __attribute__((vector_size(8)));

static inline core_floats4 core_floats4_splat(float v) { return (core_floats4){ v, v, v, v }; }

static inline core_floats4 core_floats4_load(const float *p) {
    core_floats4 v;
    memcpy(&v, p, sizeof v);
    return v;
}

static inline void core_floats4_store(float *p, core_floats4 v) { memcpy(p, &v, sizeof v); }

/* a where `take` (all bits of a lane set), else b */
static inline core_floats4 core_floats4_select(core_ints4 take, core_floats4 a, core_floats4 b) {
    return (core_floats4)((take & (core_ints4)a) | (~take & (core_ints4)b));
}

static inline core_floats4 core_floats4_abs(core_floats4 v) {
    return (core_floats4)((core_ints4)v & (core_ints4){ INT32_MAX, INT32_MAX, INT32_MAX, INT32_MAX });
}

static inline core_ints4 core_ints4_load(const int32_t *p) {
    core_ints4 v;
    memcpy(&v, p, sizeof v);
    return v;
}

static inline core_bytes16 core_bytes16_load(const uint8_t *p) {
    core_bytes16 v;
    memcpy(&v, p, sizeof v);
    return v;
}

static inline void core_bytes16_store(uint8_t *p, core_bytes16 v) { memcpy(p, &v, sizeof v); }

static inline core_doubles2 core_doubles2_splat(double v) { return (core_doubles2){ v, v }; }

/* Correctly rounded in each lane, as sqrt() is (IEEE 754): the same bits. One instruction on
 * x86-64 (SSE2 sqrtpd); GCC's vector types have no sqrt of their own. */
static inline core_doubles2 core_doubles2_sqrt(core_doubles2 v) {
#if defined(__SSE2__)
    return __builtin_ia32_sqrtpd(v);
#else
    return (core_doubles2){ __builtin_sqrt(v[0]), __builtin_sqrt(v[1]) };
#endif
}

/* Two pairs of doubles rounded to four floats, as (float) rounds each. */
static inline core_floats4 core_floats4_from_doubles(core_doubles2 lo, core_doubles2 hi) {
    core_floats2 a = __builtin_convertvector(lo, core_floats2), b = __builtin_convertvector(hi, core_floats2);
    return (core_floats4){ a[0], a[1], b[0], b[1] };
}

#endif
