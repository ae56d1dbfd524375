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
