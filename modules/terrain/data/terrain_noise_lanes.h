/* terrain_noise_lanes.h — the noise batches for one SIMD path, LANES points per step.
 *
 * Not a header of its own: terrain_noise.c includes it once per dispatch path, with
 *     LANES    points per step: 8 (SSE2, as pairs of registers; AVX2) or 16 (AVX-512)
 *     SUFFIX   the path's name, appended to each function's name (sse2, avx2, avx512)
 *     TARGET   the function attribute that enables the instruction set (empty for SSE2,
 *              x86-64's baseline)
 *     NOISE_ISA_SSE2, NOISE_ISA_AVX2 or NOISE_ISA_AVX512   which one it is
 * defined, and the vector types noise_vf##LANES, noise_vi##LANES, noise_vu##LANES declared.
 *
 * Written with GCC/Clang vector extensions rather than one set of intrinsics per width: the
 * same lines become SSE2, AVX2 or AVX-512 code, so the three paths cannot drift apart. Every
 * float operation is the scalar code's (noise3_in_column in terrain_noise.c), in the same
 * order, one lane per point: no reassociation, no FMA (TARGET never enables "fma", and the
 * file is compiled with contraction off), so each lane's result equals the scalar function's
 * (terrain__noise3, noise2_raw, terrain__multifractal2) bit for bit. Selects and sign flips
 * are integer operations on the floats' bits, as in grad3. The AVX2 and AVX-512 columns also
 * take the corner gradients from per-level tables (below), an exact rewriting of grad3. */

#define NOISE_PASTE_(a, b) a##b
#define NOISE_PASTE(a, b) NOISE_PASTE_(a, b)
#define VF NOISE_PASTE(noise_vf, LANES)
#define VI NOISE_PASTE(noise_vi, LANES)
#define VU NOISE_PASTE(noise_vu, LANES)
#define FN(name) NOISE_PASTE(name##_, SUFFIX)
#define INLINE static inline __attribute__((always_inline)) TARGET

INLINE VF FN(splat_f)(float s) {
    VF v = { 0 };   /* filled below; the initialiser keeps -O1 from warning */
    for (int i = 0; i < LANES; i++) v[i] = s;
    return v;
}

INLINE VU FN(splat_u)(uint32_t s) {
    VU v = { 0 };
    for (int i = 0; i < LANES; i++) v[i] = s;
    return v;
}

/* All-ones where the top bit of m is set: the sign bit spread over the lane. */
INLINE VU FN(top_bit_mask)(VU m) {
    return (VU)((VI)m >> 31);
}

/* mask all ones → b, all zeros → a (select_bits). */
INLINE VU FN(select)(VU mask, VU a, VU b) {
    return (a & ~mask) | (b & mask);
}

/* b where the top bit of m is set, else a. AVX2's blendv reads that bit alone (one instruction
 * for the sign spread and the three of the select); AVX-512 compiles the generic form into a
 * shift and one ternary-logic instruction; SSE2 has no blend. */
INLINE VU FN(select_top)(VU m, VU a, VU b) {
#if defined(NOISE_ISA_AVX2)
    return (VU)_mm256_blendv_ps((__m256)a, (__m256)b, (__m256)m);
#else
    return FN(select)(FN(top_bit_mask)(m), a, b);
#endif
}

/* floor_to_int: truncate, then one less where that rounded up (negative non-integers). */
INLINE VI FN(floor_to_int)(VF v) {
    VI t = __builtin_convertvector(v, VI);
    VI rounded_up = (VI)(v < __builtin_convertvector(t, VF));   /* −1 there, else 0 */
    return (VI)((VU)t + (VU)rounded_up);
}

INLINE VF FN(fade)(VF t) {
    return t * t * t * (t * (t * FN(splat_f)(6.0f) - FN(splat_f)(15.0f)) + FN(splat_f)(10.0f));
}

INLINE VF FN(lerp)(VF a, VF b, VF t) {
    return a + t * (b - a);
}

/* mix32_y with the y product (yi·HASH_Y) already formed. */
INLINE VU FN(mix_y)(VU column_hash, VU y_product) {
    VU h = column_hash ^ y_product;
    h ^= h >> 15;
    h *= FN(splat_u)(0x2c1b3c6du);
    h ^= h >> 12;
    return h;
}

/* grad3 on the hash's top four bits g = h >> 28, read as bits of h itself:
 *     g ≥ 8            bit 31 set                      u = y, else x
 *     g ∈ {12, 14}     bits 31, 30 set, bit 28 clear   v = x, else z
 *     g < 4            bits 31, 30 clear               v = y
 *     g & 1, g & 2     bits 28, 29                     shifted up to the sign bit             */
INLINE VF FN(grad3)(VU h, VF x, VF y, VF z) {
    VU xb = (VU)x, yb = (VU)y, zb = (VU)z;
    VU h1 = h << 1, h2 = h << 2, h3 = h << 3;
    VU sign = FN(splat_u)(0x80000000u);
    VU u = FN(select_top)(h, xb, yb);
    VU v = FN(select_top)(h & h1 & ~h3, zb, xb);
    v = FN(select_top)(h | h1, yb, v);
    u ^= h3 & sign;
    v ^= h2 & sign;
    return (VF)u + (VF)v;
}

/* The eight corners' values blended as noise3_in_column does (u and w from the column cell,
 * v = fade(fy)), scaled, then n > 1 ? 1 : n and n < −1 ? −1 : n (a NaN passes through both, as
 * in the scalar). */
INLINE VF FN(blend_corners)(const column_cell *c, VF fy, VF n000, VF n100, VF n010, VF n110, VF n001, VF n101,
                            VF n011, VF n111) {
    VF one = FN(splat_f)(1.0f), minus_one = FN(splat_f)(-1.0f);
    VF v = FN(fade)(fy);
    VF u = FN(splat_f)(c->u), w = FN(splat_f)(c->w);
    VF x00 = FN(lerp)(n000, n100, u), x10 = FN(lerp)(n010, n110, u);
    VF x01 = FN(lerp)(n001, n101, u), x11 = FN(lerp)(n011, n111, u);
    VF n = FN(lerp)(FN(lerp)(x00, x10, v), FN(lerp)(x01, x11, v), w) * FN(splat_f)(NOISE3_SCALE);
    n = (VF)FN(select)((VU)(n > one), (VU)n, (VU)one);
    return (VF)FN(select)((VU)(n < minus_one), (VU)n, (VU)minus_one);
}

/* LANES points of the column cell c at heights y (noise3_in_column, lane by lane). */
INLINE VF FN(noise3_lanes)(const column_cell *c, VF y) {
    VI yi = FN(floor_to_int)(y);
    VF fy = y - __builtin_convertvector(yi, VF);
    VF fx = FN(splat_f)(c->fx), fz = FN(splat_f)(c->fz);
    VF one = FN(splat_f)(1.0f);
    VF fx1 = fx - one, fy1 = fy - one, fz1 = fz - one;
    /* (yi + 1)·HASH_Y = yi·HASH_Y + HASH_Y in 32-bit unsigned arithmetic. */
    VU ky0 = (VU)yi * FN(splat_u)(HASH_Y), ky1 = ky0 + FN(splat_u)(HASH_Y);
    VU h00 = FN(splat_u)(c->h00), h10 = FN(splat_u)(c->h10), h01 = FN(splat_u)(c->h01), h11 = FN(splat_u)(c->h11);
    VF n000 = FN(grad3)(FN(mix_y)(h00, ky0), fx, fy, fz);
    VF n100 = FN(grad3)(FN(mix_y)(h10, ky0), fx1, fy, fz);
    VF n010 = FN(grad3)(FN(mix_y)(h00, ky1), fx, fy1, fz);
    VF n110 = FN(grad3)(FN(mix_y)(h10, ky1), fx1, fy1, fz);
    VF n001 = FN(grad3)(FN(mix_y)(h01, ky0), fx, fy, fz1);
    VF n101 = FN(grad3)(FN(mix_y)(h11, ky0), fx1, fy, fz1);
    VF n011 = FN(grad3)(FN(mix_y)(h01, ky1), fx, fy1, fz1);
    VF n111 = FN(grad3)(FN(mix_y)(h11, ky1), fx1, fy1, fz1);
    return FN(blend_corners)(c, fy, n000, n100, n010, n110, n001, n101, n011, n111);
}

#if !defined(NOISE_ISA_SSE2)
/* ---- the column through per-level gradient tables (AVX2, AVX-512) -------------------------
 *
 * Along a column only y changes, and a corner's gradient depends on its lattice level alone, so
 * the hashing and the gradient selection can be done once per level and corner column (four:
 * x0z0, x1z0, x0z1, x1z1) instead of once per point and corner (eight). grad3's result is
 * U + V, where at most one of U, V involves y (U = ±y needs g ≥ 8, V = ±y needs g < 4); by
 * the commutativity of IEEE addition it is, bit for bit,
 *     c + t,   t = (y_bits & a) ^ s
 * with, per level: the other term c, a = all ones and s = the y term's sign where one involves
 * y, else a = 0 and s = V's bits (then c = U). A point reads its level's (c, a, s) with a lane
 * permute from a window of LANES levels starting at its vector's lowest level. */

enum { FN(TABLE_LEVELS) = 256 };

typedef struct FN(level_tables) {
    /* [corner column][level − lowest]; LANES spare entries so any window can be loaded whole */
    uint32_t c[4][FN(TABLE_LEVELS) + LANES], a[4][FN(TABLE_LEVELS) + LANES], s[4][FN(TABLE_LEVELS) + LANES];
} FN(level_tables);

INLINE VU FN(permute)(VU table, VI index) {
#if defined(NOISE_ISA_AVX2)
    return (VU)_mm256_permutevar8x32_epi32((__m256i)table, (__m256i)index);
#else
    return (VU)_mm512_permutexvar_epi32((__m512i)index, (__m512i)table);
#endif
}

/* Levels lowest … lowest + level_count − 1 of the cell's four corner columns. */
INLINE void FN(build_level_tables)(const column_cell *cell, int lowest, int level_count, FN(level_tables) *tables) {
    uint32_t corner_hash[4] = { cell->h00, cell->h10, cell->h01, cell->h11 };
    float x_offset[4] = { cell->fx, cell->fx - 1.0f, cell->fx, cell->fx - 1.0f };
    float z_offset[4] = { cell->fz, cell->fz, cell->fz - 1.0f, cell->fz - 1.0f };
    VU lane = { 0 }, sign = FN(splat_u)(0x80000000u);
    for (int i = 0; i < LANES; i++) lane[i] = (uint32_t)i;
    for (int l = 0; l < level_count; l += LANES) {
        VU level = FN(splat_u)((uint32_t)lowest + (uint32_t)l) + lane;
        VU y_product = level * FN(splat_u)(HASH_Y);
        for (int k = 0; k < 4; k++) {
            VU h = FN(mix_y)(FN(splat_u)(corner_hash[k]), y_product);
            VU xb = (VU)FN(splat_f)(x_offset[k]), zb = (VU)FN(splat_f)(z_offset[k]);
            VU h1 = h << 1, h2 = h << 2, h3 = h << 3;
            VU u_sign = h3 & sign, v_sign = h2 & sign;
            VU u_is_y = FN(top_bit_mask)(h);              /* g ≥ 8 */
            VU v_is_y = ~FN(top_bit_mask)(h | h1);        /* g < 4 */
            VU u_other = xb ^ u_sign;                        /* U where it is not y */
            VU v_other = FN(select_top)(h & h1 & ~h3, zb, xb) ^ v_sign;   /* V where it is not y */
            VU c = FN(select)(u_is_y, u_other, v_other);
            VU a = u_is_y | v_is_y;
            VU s = FN(select)(u_is_y, FN(select)(v_is_y, v_other, v_sign), u_sign);
            memcpy(&tables->c[k][l], &c, sizeof c);
            memcpy(&tables->a[k][l], &a, sizeof a);
            memcpy(&tables->s[k][l], &s, sizeof s);
        }
    }
}

/* grad3 of corner column k at the level window[index], offset y. */
INLINE VF FN(grad3_from_table)(const FN(level_tables) *tables, int k, int window, VI index, VU y_bits) {
    VU c, a, s;
    memcpy(&c, &tables->c[k][window], sizeof c);
    memcpy(&a, &tables->a[k][window], sizeof a);
    memcpy(&s, &tables->s[k][window], sizeof s);
    return (VF)FN(permute)(c, index) + (VF)((y_bits & FN(permute)(a, index)) ^ FN(permute)(s, index));
}

/* noise3_lanes with the corner gradients from the tables; every lane's level yi and yi + 1
 * lies in window … window + LANES − 1 (relative to the tables' lowest level). */
INLINE VF FN(noise3_lanes_tables)(const column_cell *c, const FN(level_tables) *tables, int window, VI index, VF fy) {
    VF one = FN(splat_f)(1.0f);
    VF fy1 = fy - one;
    VU fy_bits = (VU)fy, fy1_bits = (VU)fy1;
    VI index1 = index + 1;
    VF n000 = FN(grad3_from_table)(tables, 0, window, index, fy_bits);
    VF n100 = FN(grad3_from_table)(tables, 1, window, index, fy_bits);
    VF n010 = FN(grad3_from_table)(tables, 0, window, index1, fy1_bits);
    VF n110 = FN(grad3_from_table)(tables, 1, window, index1, fy1_bits);
    VF n001 = FN(grad3_from_table)(tables, 2, window, index, fy_bits);
    VF n101 = FN(grad3_from_table)(tables, 3, window, index, fy_bits);
    VF n011 = FN(grad3_from_table)(tables, 2, window, index1, fy1_bits);
    VF n111 = FN(grad3_from_table)(tables, 3, window, index1, fy1_bits);
    return FN(blend_corners)(c, fy, n000, n100, n010, n110, n001, n101, n011, n111);
}
#endif

/* out[j] = noise at (c's column, y0 + j·dy) for j < count. */
static TARGET void FN(noise3_column)(const column_cell *c, float y0, float dy, int count, float *out) {
    VI lane = { 0 };
    for (int i = 0; i < LANES; i++) lane[i] = i;
    VF y0v = FN(splat_f)(y0), dyv = FN(splat_f)(dy);
    int vectors = (count + LANES - 1) / LANES;
#if !defined(NOISE_ISA_SSE2)
    /* The levels the column's points (and the last vector's spare lanes) reach: y is monotone
     * in j, so the first and the last point bound them. Tables pay where levels are no more
     * than points; beyond TABLE_LEVELS, or for a vector spanning more than its window, the
     * direct form below. */
    FN(level_tables) tables;
    int64_t first_level = floor_to_int(y0 + 0.0f * dy), last_level = floor_to_int(y0 + (float)(vectors * LANES - 1) * dy);
    int64_t lowest = first_level < last_level ? first_level : last_level;
    int64_t level_count = (first_level < last_level ? last_level : first_level) + 2 - lowest;
    bool use_tables = count > 0 && level_count <= FN(TABLE_LEVELS) && level_count <= (int64_t)vectors * LANES;
    if (use_tables) FN(build_level_tables)(c, (int)lowest, (int)level_count, &tables);
#endif
    for (int v = 0; v < vectors; v++) {
        int j = v * LANES;
        /* y0 + (float)(first + j)·dy, as noise3_block computes it */
        VF y = y0v + __builtin_convertvector(lane + j, VF) * dyv;
        VF n;
#if !defined(NOISE_ISA_SSE2)
        VI yi = FN(floor_to_int)(y);
        int window = yi[0] < yi[LANES - 1] ? yi[0] : yi[LANES - 1];
        int64_t window_top = (int64_t)(yi[0] < yi[LANES - 1] ? yi[LANES - 1] : yi[0]) + 1;
        if (use_tables && window_top - window < LANES) {
            VF fy = y - __builtin_convertvector(yi, VF);
            n = FN(noise3_lanes_tables)(c, &tables, (int)(window - lowest), (VI)((VU)yi - (uint32_t)window), fy);
        } else
#endif
            n = FN(noise3_lanes)(c, y);
        memcpy(out + j, &n, (size_t)(count - j < LANES ? count - j : LANES) * sizeof(float));
    }
}

/* ---- 2D: the row batch and the multifractal's row ---------------------------------------- */

INLINE VU FN(mix32)(VU h) {
    h ^= h >> 16;
    h *= FN(splat_u)(0x7feb352du);
    h ^= h >> 15;
    h *= FN(splat_u)(0x846ca68bu);
    h ^= h >> 16;
    return h;
}

/* grad2 on the hash's top three bits g = h >> 29: g ≥ 4 (bit 31) swaps x and z; g & 1 and
 * g & 2 (bits 29, 30) flip the signs. */
INLINE VF FN(grad2)(VU h, VF x, VF z) {
    VU xb = (VU)x, zb = (VU)z;
    VU sign = FN(splat_u)(0x80000000u);
    VU u = FN(select_top)(h, xb, zb);
    VU v = FN(select_top)(h, zb, xb);
    u ^= (h << 2) & sign;
    v ^= (h << 1) & sign;
    return (VF)u + FN(splat_f)(2.0f) * (VF)v;
}

/* noise2_raw, lane by lane; cell_x_product and cell_z_product are the cells times HASH_X and
 * HASH_Y. */
INLINE VF FN(noise2_raw)(uint32_t seed, VU cell_x_product, VU cell_z_product, VF x, VF z) {
    VI xi = FN(floor_to_int)(x), zi = FN(floor_to_int)(z);
    VF fx = x - __builtin_convertvector(xi, VF), fz = z - __builtin_convertvector(zi, VF);
    VF one = FN(splat_f)(1.0f);
    /* (cell + xi + 1)·HASH_X = xi·HASH_X + cell·HASH_X + HASH_X, and so for z, in 32-bit
     * unsigned arithmetic: noise2_raw's lattice indices. */
    VU kx0 = (VU)xi * FN(splat_u)(HASH_X) + cell_x_product, kz0 = (VU)zi * FN(splat_u)(HASH_Y) + cell_z_product;
    VU kx1 = kx0 + FN(splat_u)(HASH_X), kz1 = kz0 + FN(splat_u)(HASH_Y);
    VU seeds = FN(splat_u)(seed);
    VU hx0 = FN(mix32)(seeds ^ kx0), hx1 = FN(mix32)(seeds ^ kx1);
    VF fx1 = fx - one, fz1 = fz - one;
    VF n00 = FN(grad2)(FN(mix_y)(hx0, kz0), fx, fz);
    VF n10 = FN(grad2)(FN(mix_y)(hx1, kz0), fx1, fz);
    VF n01 = FN(grad2)(FN(mix_y)(hx0, kz1), fx, fz1);
    VF n11 = FN(grad2)(FN(mix_y)(hx1, kz1), fx1, fz1);
    VF u = FN(fade)(fx), w = FN(fade)(fz);
    return FN(lerp)(FN(lerp)(n00, n10, u), FN(lerp)(n01, n11, u), w) * FN(splat_f)(NOISE2_SCALE);
}

/* LANES floats from xs[0 … available−1], the last repeated past the end (noise2_row's tail). */
INLINE VF FN(load_padded)(const float *xs, int available) {
    if (available >= LANES) {
        VF v;
        memcpy(&v, xs, sizeof v);
        return v;
    }
    VF v = FN(splat_f)(xs[0]);
    memcpy(&v, xs, (size_t)available * sizeof(float));
    return v;
}

INLINE void FN(store_partial)(float *out, VF v, int available) {
    memcpy(out, &v, (size_t)(available < LANES ? available : LANES) * sizeof(float));
}

/* noise2_row: out[j] = noise2_raw at the origin o's cells, offsets o->offset_x + dxs[j]·scale and
 * o->offset_z. */
static TARGET void FN(noise2_row)(uint32_t seed, const noise2_origin *o, const float *dxs, float scale, int count,
                                  float *out) {
    VF scale_v = FN(splat_f)(scale), x0 = FN(splat_f)(o->offset_x), z_v = FN(splat_f)(o->offset_z);
    VU cell_x = FN(splat_u)(o->cell_x * HASH_X), cell_z = FN(splat_u)(o->cell_z * HASH_Y);
    for (int j = 0; j < count; j += LANES) {
        VF x = x0 + FN(load_padded)(dxs + j, count - j) * scale_v;
        FN(store_partial)(out + j, FN(noise2_raw)(seed, cell_x, cell_z, x, z_v), count - j);
    }
}

/* inverse_sqrt, lane by lane. */
INLINE VF FN(inverse_sqrt)(VF v) {
    VF r = (VF)(FN(splat_u)(0x5f3759dfu) - ((VU)v >> 1));
    VF half = FN(splat_f)(0.5f), three_halves = FN(splat_f)(1.5f);
    r = r * (three_halves - half * v * r * r);
    return r * (three_halves - half * v * r * r);
}

/* mf_block over the row: each lane carries one point's warp state through the octaves. */
static TARGET void FN(multifractal2_row)(const mf_octave *octaves, int octave_count, float total, const float *dxs,
                                         int count, float *out) {
    VF e1x = FN(splat_f)(WARP_E1[0]), e1z = FN(splat_f)(WARP_E1[1]);
    VF e2x = FN(splat_f)(WARP_E2[0]), e2z = FN(splat_f)(WARP_E2[1]);
    VF e3x = FN(splat_f)(WARP_E3[0]), e3z = FN(splat_f)(WARP_E3[1]);
    VF tiny = FN(splat_f)(1e-12f);
    VF inverse_total = FN(splat_f)(total > 0.0f ? 1.0f / total : 0.0f);
    for (int j = 0; j < count; j += LANES) {
        VF dx = FN(load_padded)(dxs + j, count - j);
        VF sum = FN(splat_f)(0.0f), rho_x = FN(splat_f)(1.0f), rho_z = FN(splat_f)(0.0f);
        VF t_x = FN(splat_f)(0.0f), t_z = FN(splat_f)(0.0f);
        for (int k = 0; k < octave_count; k++) {
            const mf_octave *o = &octaves[k];
            VF warp = FN(splat_f)(o->warp), cos_b = FN(splat_f)(o->cos_b), sin_b = FN(splat_f)(o->sin_b);
            VF frequency = FN(splat_f)(o->frequency);
            VU cell_x = FN(splat_u)(o->cell_x * HASH_X), cell_z = FN(splat_u)(o->cell_z * HASH_Y);
            /* mf_step, term for term */
            VF wx = (rho_x * t_x - rho_z * t_z) * warp;
            VF wz = (rho_z * t_x + rho_x * t_z) * warp;
            VF px = FN(splat_f)(o->offset_x) + (cos_b * dx + wx) * frequency;
            VF pz = FN(splat_f)(o->offset_z) + (sin_b * dx + wz) * frequency;
            VF h = sum + FN(splat_f)(o->amplitude) * FN(noise2_raw)(o->seed, cell_x, cell_z, px, pz);
            VF roughness = FN(splat_f)(o->r0) - h;
            VF rx = rho_x + e1x * roughness + e2x;
            VF rz = rho_z + e1z * roughness + e2z;
            VF length2 = rx * rx + rz * rz;
            VF inverse = FN(inverse_sqrt)(length2 + tiny);
            rho_x = rx * inverse;
            rho_z = rz * inverse;
            t_x = e3x * h;
            t_z = e3z * roughness;
            sum = h;
        }
        FN(store_partial)(out + j, sum * inverse_total, count - j);
    }
}

#undef VF
#undef VI
#undef VU
#undef FN
#undef INLINE
#undef NOISE_PASTE
#undef NOISE_PASTE_
