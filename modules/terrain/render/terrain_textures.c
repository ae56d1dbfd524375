/* terrain_textures.c — the procedural material textures, made on the CPU when a renderer is made:
 * per material a base layer (8 m a repeat) and a detail layer (1 m a repeat), each carrying its
 * own normal map, and one macro layer (200 m) that varies brightness, hue and the scale blend so
 * that hillsides show no grid of repeats. Layouts in terrain_internal.h; the shader side is
 * shaders/terrain.frag. */
#include "terrain/render/terrain_render_internal.h"

#include "core/core.h"
#include "trace/trace.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <string.h>
#include <unistd.h>

/* What every material's base layer is multiplied by: the layers store a shade (and relief), the
 * colour is the tint's, so that one fetch gives albedo and normal (llvmpipe pays per fetch). */
static const float material_tints[TERRAIN__MATERIAL_LAYERS][3] = {
    { 0.52f, 0.48f, 0.43f },   /* bedrock */
    { 0.86f, 0.76f, 0.55f },   /* sand */
    { 0.48f, 0.47f, 0.46f },   /* rocks */
    { 0.30f, 0.33f, 0.28f },   /* water bed */
};

/* Relief in metres per unit of height, per material: how deep the base (8 m) and detail (1 m)
 * layers' height fields are when they are turned into normals. */
static const float base_relief[TERRAIN__MATERIAL_LAYERS] = { 0.25f, 0.04f, 0.12f, 0.05f };
static const float detail_relief[TERRAIN__MATERIAL_LAYERS] = { 0.012f, 0.004f, 0.02f, 0.003f };

/* ---- tiling noise ---- */

/* A lattice point's hash; x and y already wrapped into their periods. One mix per point: the
 * textures' start-up cost is mostly these. */
static inline uint64_t texture_point_hash(uint64_t seed, int x, int y) {
    return core_hash_u64(((uint64_t)(uint32_t)x << 32 | (uint32_t)y) ^ (seed * 0x9e3779b97f4a7c15ull));
}

static inline int texture_wrap(int i, int period) { return ((i % period) + period) % period; }

static inline float texture_unit(uint64_t h) { return (float)(h >> 40) * (1.0f / 16777216.0f); }

/* Value noise on a lattice that wraps every period_x by period_y cells, so the texture tiles
 * seamlessly (indices wrapped once per sample: the divisions cost more than the hashes). */
static float texture_value_noise2(uint64_t seed, float x, float y, int period_x, int period_y) {
    int xi = (int)floorf(x), yi = (int)floorf(y);
    float fx = x - (float)xi, fy = y - (float)yi;
    fx = fx * fx * (3 - 2 * fx);
    fy = fy * fy * (3 - 2 * fy);
    int x0 = texture_wrap(xi, period_x), y0 = texture_wrap(yi, period_y);
    int x1 = x0 + 1 == period_x ? 0 : x0 + 1, y1 = y0 + 1 == period_y ? 0 : y0 + 1;
    float a = texture_unit(texture_point_hash(seed, x0, y0)), b = texture_unit(texture_point_hash(seed, x1, y0));
    float c = texture_unit(texture_point_hash(seed, x0, y1)), d = texture_unit(texture_point_hash(seed, x1, y1));
    return (a + (b - a) * fx) + ((c + (d - c) * fx) - (a + (b - a) * fx)) * fy;
}

static float texture_value_noise(uint64_t seed, float x, float y, int period) {
    return texture_value_noise2(seed, x, y, period, period);
}

/* fBm of tiling value noise over the unit square (u, v ∈ [0, 1)), first octave cells_u by
 * cells_v across (unequal for stretched patterns such as strata, which still tile). */
static float texture_fbm2(uint64_t seed, float u, float v, int cells_u, int cells_v, int octaves) {
    float sum = 0, amplitude = 0.5f, total = 0;
    for (int o = 0; o < octaves; o++, cells_u *= 2, cells_v *= 2, amplitude *= 0.5f) {
        sum += amplitude * texture_value_noise2(seed + (uint64_t)o, u * (float)cells_u, v * (float)cells_v, cells_u, cells_v);
        total += amplitude;
    }
    return sum / total;
}

static float texture_fbm(uint64_t seed, float u, float v, int cells, int octaves) {
    return texture_fbm2(seed, u, v, cells, cells, octaves);
}

/* Cellular noise (Worley) on a wrapping grid of `period` cells, one jittered point per cell:
 * distances to the nearest and second nearest points (in cells) and the nearest one's hash. */
typedef struct texture_cell { float f1, f2; uint64_t id; } texture_cell;

static texture_cell texture_cells(uint64_t seed, float u, float v, int period) {
    float x = u * (float)period, y = v * (float)period;
    int xi = (int)floorf(x), yi = (int)floorf(y);
    texture_cell c = { 9, 9, 0 };
    for (int dy = -1; dy <= 1; dy++)
        for (int dx = -1; dx <= 1; dx++) {
            uint64_t h = texture_point_hash(seed, texture_wrap(xi + dx, period), texture_wrap(yi + dy, period));
            float px = (float)(xi + dx) + 0.15f + 0.7f * (float)(h & 0xffff) / 65535.0f;
            float py = (float)(yi + dy) + 0.15f + 0.7f * (float)((h >> 16) & 0xffff) / 65535.0f;
            float d = sqrtf((px - x) * (px - x) + (py - y) * (py - y));
            if (d < c.f1) { c.f2 = c.f1; c.f1 = d; c.id = h; }
            else if (d < c.f2) c.f2 = d;
        }
    return c;
}

/* ---- what each layer looks like: a shade (albedo factor) and a height ---- */

typedef struct texture_texel { float shade, height; } texture_texel;

/* Base layers, 8 m a repeat: the look of a material from a few metres to a few hundred. */
static texture_texel base_texel(int layer, float u, float v) {
    if (layer == 0) {        /* bedrock: grey-brown strata with cracks */
        /* Stretched 4:1 along u with a lattice of 2 × 8 cells: it tiles (a u·0.25 scale on an
         * 8-cell lattice would not, leaving a seam every 8 m). */
        float strata = texture_fbm2(11, u, v, 2, 8, 5);
        float grain = texture_fbm(12, u, v, 32, 3);
        return (texture_texel){ 0.45f + 0.35f * strata + 0.2f * grain, strata + 0.3f * grain };
    } else if (layer == 1) { /* sand: fine, warm, with ripples */
        float grain = texture_fbm(21, u, v, 64, 3);
        float ripple = 0.5f + 0.5f * sinf((u * 12.0f + texture_fbm(22, u, v, 4, 3) * 3.0f) * 6.2831853f);
        return (texture_texel){ 0.8f + 0.12f * grain + 0.08f * ripple, ripple + 0.2f * grain };
    } else if (layer == 2) { /* rocks: pebbles as cells of high noise */
        float cells = texture_fbm(31, u, v, 16, 2);
        float detail = texture_fbm(32, u, v, 64, 2);
        return (texture_texel){ 0.35f + 0.5f * cells * cells + 0.15f * detail, cells * cells + 0.2f * detail };
    } else {                 /* water bed: dark silt */
        float silt = texture_fbm(41, u, v, 16, 4);
        return (texture_texel){ 0.5f + 0.3f * silt, silt };
    }
}

/* Detail layers, 1 m a repeat: what the ground shows a metre or two away. The shade is a
 * multiplier, scaled to a mean of 1 afterwards, so the detail never changes a region's colour. */
static texture_texel detail_texel(int layer, float u, float v) {
    if (layer == 0) {        /* bedrock: cracks along the edges of cells, not all of them open
                                (a noise picks which), over fine strata and grain */
        /* The cells' coordinates bent by a tiling noise: crooked cracks, not straight edges. */
        float bend_u = 0.08f * (texture_fbm(115, u, v, 4, 2) - 0.5f), bend_v = 0.08f * (texture_fbm(116, u, v, 4, 2) - 0.5f);
        texture_cell c = texture_cells(111, u + bend_u, v + bend_v, 5);
        float open = fminf(fmaxf((texture_fbm(114, u, v, 4, 2) - 0.4f) * 5.0f, 0.0f), 1.0f);
        float crack = (1.0f - fminf((c.f2 - c.f1) * 16.0f, 1.0f)) * open;
        float strata = 0.5f + 0.5f * sinf((v * 20.0f + texture_fbm(112, u, v, 3, 2) * 2.0f) * 6.2831853f);
        float grain = texture_fbm(113, u, v, 64, 2);
        return (texture_texel){ 0.9f + 0.05f * strata + 0.25f * grain - 0.35f * crack,
                                0.3f * strata + 0.6f * grain - 1.5f * crack };
    } else if (layer == 1) { /* sand: grains (two texels each) over small wind ripples */
        float grain = texture_value_noise(121, u * 128.0f, v * 128.0f, 128);
        float ripple = 0.5f + 0.5f * sinf((u * 8.0f + v * 1.0f + texture_fbm(122, u, v, 2, 2) * 1.5f) * 6.2831853f);
        return (texture_texel){ 0.85f + 0.3f * grain + 0.06f * ripple, ripple + 0.5f * grain };
    } else if (layer == 2) { /* rocks: pebbles, domes of cellular noise with dark gaps between */
        texture_cell c = texture_cells(131, u, v, 10);
        float gap = fminf((c.f2 - c.f1) * 6.0f, 1.0f);
        float dome = fmaxf(0.0f, 1.0f - c.f1 * c.f1) * gap;
        float tone = 0.75f + 0.5f * (float)(c.id >> 40) * (1.0f / 16777216.0f);
        float grain = texture_fbm(132, u, v, 64, 2);
        return (texture_texel){ tone * (0.45f + 0.55f * gap) * (0.9f + 0.2f * grain), dome + 0.1f * grain };
    } else {                 /* water bed: soft silt with a fine grain */
        float silt = texture_fbm(141, u, v, 8, 4);
        float grain = texture_fbm(142, u, v, 64, 2);
        return (texture_texel){ 0.85f + 0.2f * silt + 0.1f * grain, silt + 0.2f * grain };
    }
}

/* ---- normals from heights ---- */

/* Tangent-space normals of a tiling height field by central differences (wrapping), written to
 * two channels as 0.5 + 0.5·n; x along u, y along v, z out of the surface (rebuilt in the shader). */
static void texture_normals(const float *height, int size, float texel_metres, float relief,
                            uint8_t *rgba, int channel) {
    for (int y = 0; y < size; y++)
        for (int x = 0; x < size; x++) {
            int xl = (x + size - 1) % size, xr = (x + 1) % size, yd = (y + size - 1) % size, yu = (y + 1) % size;
            float du = (height[y * size + xr] - height[y * size + xl]) * relief / (2 * texel_metres);
            float dv = (height[yu * size + x] - height[yd * size + x]) * relief / (2 * texel_metres);
            float length = sqrtf(du * du + dv * dv + 1);
            uint8_t *t = rgba + ((size_t)y * (size_t)size + (size_t)x) * 4;
            t[channel] = (uint8_t)lrintf(127.5f - 127.5f * du / length);
            t[channel + 1] = (uint8_t)lrintf(127.5f - 127.5f * dv / length);
        }
}

static uint8_t texture_unorm(float value) { return (uint8_t)lrintf(fminf(fmaxf(value, 0.0f), 1.0f) * 255.0f); }

/* Writes value/mean·0.5 to one channel, so the channel reads 0.5 on average: a multiplier of
 * 2·texel with a mean of 1 (to within the rounding of 8 bits). */
static void texture_store_mean_one(const float *value, size_t count, uint8_t *rgba, int channel) {
    double sum = 0;
    for (size_t i = 0; i < count; i++) sum += value[i];
    float scale = (float)(0.5 * (double)count / sum);
    for (size_t i = 0; i < count; i++) rgba[i * 4 + (size_t)channel] = texture_unorm(value[i] * scale);
}

/* The macro layer, 200 m a repeat: R brightness and G hue (both with a mean of 1 after
 * decoding, 2·texel), B the share of the 25 m sample in the base's scale blend. */
static void macro_layer(uint8_t *rgba, float *scratch) {
    const int size = TERRAIN__DETAIL_SIZE;
    const size_t count = (size_t)size * (size_t)size;
    for (int pass = 0; pass < 2; pass++) {
        for (int y = 0; y < size; y++)
            for (int x = 0; x < size; x++) {
                float u = (float)x / (float)size, v = (float)y / (float)size;
                float n = texture_fbm(pass ? 152 : 151, u, v, 4, 4);
                scratch[y * size + x] = pass ? 0.8f + 0.4f * n : 0.7f + 0.6f * n;
            }
        texture_store_mean_one(scratch, count, rgba, pass);
    }
    for (int y = 0; y < size; y++)
        for (int x = 0; x < size; x++) {
            float u = (float)x / (float)size, v = (float)y / (float)size;
            uint8_t *t = rgba + ((size_t)y * (size_t)size + (size_t)x) * 4;
            t[2] = texture_unorm(texture_fbm(153, u, v, 8, 3));
            t[3] = 255;
        }
}

/* ---- making the layers: nine independent tasks, on a few threads ---- */

typedef struct texture_task_list {
    terrain__material_texels *out;
    atomic_int next;
} texture_task_list;

/* Base layer `layer`: shade in R (quantised as the shader reads it), normals in GB. */
static void make_base_layer(terrain__material_texels *out, int layer, float *height) {
    const int size = TERRAIN__BASE_SIZE;
    const size_t count = (size_t)size * (size_t)size;
    uint8_t *rgba = out->base + count * 4 * (size_t)layer;
    double shade_sum = 0;
    for (int y = 0; y < size; y++)
        for (int x = 0; x < size; x++) {
            texture_texel t = base_texel(layer, (float)x / (float)size, (float)y / (float)size);
            uint8_t *texel = rgba + ((size_t)y * (size_t)size + (size_t)x) * 4;
            height[y * size + x] = t.height;
            texel[0] = texture_unorm(t.shade);
            texel[3] = 255;
            shade_sum += texel[0] / 255.0;
        }
    texture_normals(height, size, TERRAIN__BASE_METRES / (float)size, base_relief[layer], rgba, 1);
    /* What the layer's mipmaps tend to far away, in the colour the shader makes of it. */
    for (int c = 0; c < 3; c++) {
        out->tints[layer][c] = material_tints[layer][c];
        out->means[layer][c] = (float)(shade_sum / (double)count) * material_tints[layer][c];
    }
}

static void make_detail_layer(terrain__material_texels *out, int layer, float *height, float *shade) {
    const int size = TERRAIN__DETAIL_SIZE;
    const size_t count = (size_t)size * (size_t)size;
    uint8_t *rgba = out->detail + count * 4 * (size_t)layer;
    for (int y = 0; y < size; y++)
        for (int x = 0; x < size; x++) {
            texture_texel t = detail_texel(layer, (float)x / (float)size, (float)y / (float)size);
            height[y * size + x] = t.height;
            shade[y * size + x] = fmaxf(t.shade, 0.05f);
            rgba[((size_t)y * (size_t)size + (size_t)x) * 4 + 3] = 255;
        }
    texture_store_mean_one(shade, count, rgba, 0);
    texture_normals(height, size, TERRAIN__DETAIL_METRES / (float)size, detail_relief[layer], rgba, 1);
}

enum { TEXTURE_TASKS = 2 * TERRAIN__MATERIAL_LAYERS + 1 };

static void *texture_worker(void *user) {
    texture_task_list *list = user;
    terrain__material_texels *out = list->out;
    size_t count = (size_t)TERRAIN__DETAIL_SIZE * TERRAIN__DETAIL_SIZE;
    if ((size_t)TERRAIN__BASE_SIZE * TERRAIN__BASE_SIZE > count) count = (size_t)TERRAIN__BASE_SIZE * TERRAIN__BASE_SIZE;
    float *height = core_alloc(count * sizeof *height), *shade = core_alloc(count * sizeof *shade);
    /* Detail layers first: the rocks' cellular noise is the longest task. */
    for (int task; (task = atomic_fetch_add(&list->next, 1)) < TEXTURE_TASKS;) {
        if (task < TERRAIN__MATERIAL_LAYERS) make_detail_layer(out, TERRAIN__MATERIAL_LAYERS - 1 - task, height, shade);
        else if (task < 2 * TERRAIN__MATERIAL_LAYERS) make_base_layer(out, task - TERRAIN__MATERIAL_LAYERS, height);
        else macro_layer(out->detail + count * 4 * TERRAIN__MATERIAL_LAYERS, shade);
    }
    core_free(height, count * sizeof *height);
    core_free(shade, count * sizeof *shade);
    return NULL;
}

/* Every program and test makes these at start-up, so the layers are made on up to four threads
 * of their own (the renderer has no job system). Each layer depends only on its coordinates:
 * the result is the same on any number of threads. */
void terrain__material_texels_make(terrain__material_texels *out) {
    TRACE_ZONE("terrain_material_texels");
    const size_t base_count = (size_t)TERRAIN__BASE_SIZE * TERRAIN__BASE_SIZE;
    const size_t detail_count = (size_t)TERRAIN__DETAIL_SIZE * TERRAIN__DETAIL_SIZE;
    *out = (terrain__material_texels){
        .base_bytes = base_count * 4 * TERRAIN__MATERIAL_LAYERS,
        .detail_bytes = detail_count * 4 * TERRAIN__DETAIL_LAYERS };
    out->base = core_alloc(out->base_bytes);
    out->detail = core_alloc(out->detail_bytes);
    texture_task_list list = { .out = out };
    atomic_init(&list.next, 0);
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    int helpers = cores > 4 ? 3 : cores > 1 ? (int)cores - 1 : 0;
    pthread_t threads[3];
    int started = 0;
    for (int i = 0; i < helpers; i++)
        if (pthread_create(&threads[started], NULL, texture_worker, &list) == 0) started++;
    texture_worker(&list);   /* this thread works too; alone if no thread could start */
    for (int i = 0; i < started; i++) pthread_join(threads[i], NULL);
}

void terrain__material_texels_free(terrain__material_texels *texels) {
    core_free(texels->base, texels->base_bytes);
    core_free(texels->detail, texels->detail_bytes);
    *texels = (terrain__material_texels){ 0 };
}
