/* grass_texture.c — the blade texture of a tuft, generated once: a handful of tapering, leaning,
 * slightly curved blades, dark at the root and lighter at the tip. Its mean colour is near the
 * terrain shader's grass tint (bedrock × (0.55, 0.85, 0.45), about (0.21, 0.30, 0.14)), so far
 * tufts and the tinted ground between them read as one meadow. */
#include "vegetation_internal.h"

#include "core/core.h"

#include <math.h>

#define BLADE_TEXTURE_SIZE 128
#define BLADE_COUNT 16

typedef struct blade {
    float root, lean, height, width;      /* texture units: root x, tip's sideways lean, … */
    float shade;                          /* colour variation, around 1 */
} blade;

static float blade_random(uint64_t n) { return (float)(core_hash_u64(n) >> 40) * (1.0f / 16777216.0f); }

static blade blade_make(int index) {
    uint64_t base = 0x626c616465ull * 131 + (uint64_t)index * 8;   /* "blade" */
    return (blade){ .root = 0.12f + 0.76f * blade_random(base),
                    .lean = (blade_random(base + 1) - 0.5f) * 0.5f,
                    .height = 0.55f + 0.45f * blade_random(base + 2),
                    .width = 0.025f + 0.025f * blade_random(base + 3),
                    .shade = 0.85f + 0.3f * blade_random(base + 4) };
}

/* Whether texel (u, v) (v up from the root) lies on the blade, and how far up it is (0 … 1). */
static bool blade_covers(const blade *b, float u, float v, float *along) {
    if (v >= b->height) return false;
    float t = v / b->height;
    float centre = b->root + b->lean * t * t;              /* curving more towards the tip */
    float half = b->width * (1.0f - t);                    /* tapering to a point */
    *along = t;
    return fabsf(u - centre) <= half;
}

gfx_texture grass__blade_texture(void) {
    const int size = BLADE_TEXTURE_SIZE;
    uint8_t *texels = core_calloc((size_t)size * (size_t)size, 4);
    blade blades[BLADE_COUNT];
    for (int i = 0; i < BLADE_COUNT; i++) blades[i] = blade_make(i);
    /* Between blades: the blades' mean colour, transparent, so mipmaps fringe no dark edge. */
    for (size_t t = 0; t < (size_t)size * (size_t)size; t++) {
        texels[4 * t] = 56, texels[4 * t + 1] = 82, texels[4 * t + 2] = 28;
    }
    for (int y = 0; y < size; y++)
        for (int x = 0; x < size; x++) {
            float u = ((float)x + 0.5f) / (float)size, v = ((float)y + 0.5f) / (float)size;
            for (int i = BLADE_COUNT - 1; i >= 0; i--) {     /* later blades in front */
                float t;
                if (!blade_covers(&blades[i], u, v, &t)) continue;
                const float root[3] = { 0.15f, 0.26f, 0.08f }, tip[3] = { 0.40f, 0.52f, 0.19f };
                uint8_t *texel = texels + ((size_t)y * (size_t)size + (size_t)x) * 4;
                for (int c = 0; c < 3; c++)
                    texel[c] = (uint8_t)fminf(255.0f, (root[c] + (tip[c] - root[c]) * t) * blades[i].shade * 255.0f);
                texel[3] = 255;
                break;
            }
        }
    /* Row 0 is the root: texture coordinate y runs up the blade. */
    gfx_texture texture = gfx_texture_create(&(gfx_texture_desc){ .width = size, .height = size, .data = texels,
                                                                  .mipmaps = true, .clamp = true });
    core_free(texels, (size_t)size * (size_t)size * 4);
    return texture;
}
