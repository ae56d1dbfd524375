// materials.glsl — what terrain.frag and clipmap.frag share about the material textures
// (made in modules/terrain/render/terrain_textures.c; layouts in terrain_render_internal.h).

uniform sampler2DArray u_materials;   // per material, 8 m a repeat: R shade, GB normal x, y
uniform sampler2DArray u_detail;      // per material, 1 m: R albedo multiplier / 2, GB normal;
                                      // layer 4, 200 m: the macro variation
uniform vec3 u_material_tints[4];     // albedo = tint · shade
uniform float u_mean_shades[4];       // each base layer's mean shade
uniform float u_texture_scale;        // base repeats per metre (1 / 8 m)
uniform float u_texture_scale2;       // the base again, coarser (1 / 25 m), against repeats
uniform float u_macro_scale;          // macro repeats per metre (1 / 200 m)
uniform float u_scale_blend;          // 1: mix in the 25 m sample; 0: not (the low quality)

const float MACRO_LAYER = 4.0;

// Low-frequency variation over the ground's plan, so a hillside at 200 m shows no grid of 8 m
// repeats: brightness and a warm/cool hue shift, both with a mean of 1 over the layer (the far
// colours stay the material means), and how much of the coarser base to blend in.
// Level 3 of the 200 m layer (32², 6 m a texel) holds all its octaves: a fixed level, so the
// meshes sample it per vertex (their spacing is 1–8 m), which saves a fetch per pixel.
vec4 macro_sample(vec3 texture_position) {
    return textureLod(u_detail, vec3(texture_position.xz * u_macro_scale, MACRO_LAYER), 3.0);
}

vec3 macro_tint(vec4 macro) {
    float brightness = macro.r * 2.0;
    float hue = macro.g * 2.0 - 1.0;
    return brightness * vec3(1.0 + 0.4 * hue, 1.0, 1.0 - 0.4 * hue);
}

// The share of the 25 m sample in the base: varies over the plan so neither scale's repeats
// line up into a grid. Zero skips the sample's fetch (llvmpipe skips what no pixel needs).
float macro_coarse_share(vec4 macro) { return (0.2 + 0.5 * macro.b) * u_scale_blend; }

// 000 §6: weights |n_i|^p / Σ|n_j|^p, i.e. each axis' share of ‖n‖_p^p, with p = 8.
vec3 triplanar_weights(vec3 n) {
    vec3 a = abs(n);
    vec3 w = a * a; w *= w; w *= w;           // |n|^8
    return w / max(w.x + w.y + w.z, 1e-6);
}

// Two of three, and two of four. llvmpipe runs both sides of a branch that differs between
// pixels, fetches included, so the projections and materials a pixel hardly uses cost as much
// as those it uses. Each pixel reads the two largest of each, chosen per pixel (the texture
// array's layer and the projection's axes are just values), less the largest one left out:
// where the second and third swap, the second's weight has reached zero, so the blend stays
// continuous. terrain.frag reads 4 base fetches in place of 12 with it, clipmap.frag 2 in
// place of 3 per material and scale.
struct pick {
    ivec2 index;                              // the largest, the second
    vec2 weight;                              // theirs less the third's, summing to 1
};

pick pick_two_of_three(vec3 w) {
    int first = w.x >= w.y ? (w.x >= w.z ? 0 : 2) : (w.y >= w.z ? 1 : 2);
    int last = w.x < w.y ? (w.x < w.z ? 0 : 2) : (w.y < w.z ? 1 : 2);
    int second = 3 - first - last;
    vec2 kept = vec2(w[first], w[second]) - w[last];
    return pick(ivec2(first, second), kept / max(kept.x + kept.y, 1e-6));
}

pick pick_two_of_four(vec4 w) {
    // Sorted by a network of five compare-exchanges on (weight, index) pairs, largest first.
    vec2 a = vec2(w.x, 0.0), b = vec2(w.y, 1.0), c = vec2(w.z, 2.0), d = vec2(w.w, 3.0), t;
    if (b.x > a.x) { t = a; a = b; b = t; }
    if (d.x > c.x) { t = c; c = d; d = t; }
    if (c.x > a.x) { t = a; a = c; c = t; }
    if (d.x > b.x) { t = b; b = d; d = t; }
    if (c.x > b.x) { t = b; b = c; c = t; }
    vec2 kept = vec2(a.x, b.x) - c.x;
    return pick(ivec2(a.y, b.y), kept / max(kept.x + kept.y, 1e-6));
}

// Projection `axis` of a point: x reads (z, y), y reads (x, z), z reads (x, y).
vec2 projected(vec3 p, int axis) { return axis == 0 ? p.zy : axis == 1 ? p.xz : p.xy; }
