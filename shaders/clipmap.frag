#version 450 core
// clipmap.frag — the far terrain's colour, made to read like the meshes' (terrain.frag) from far
// away: bedrock tinted by height bands and slope (002 §4.1: α = (1 − n_y)·90°), sand where the
// generator lays it (slopes below sand_max_slope), the sea over ground below sea level, the
// lakes over their beds, then the sun, sky ambient and fog of common.glsl, and towards the end
// of the world a fade into the sky (002 §4.4).

#include "common.glsl"
#include "materials.glsl"
#include "shadow.glsl"
#include "water_optics.glsl"

in vec3 v_relative_position;
in vec3 v_normal;
in float v_height;
in float v_lake_depth;                // metres of lake water over the ground here (≤ 0: dry)

uniform vec3 u_bedrock_mean, u_sand_mean;  // their layers' mean colours (tint · mean shade)
uniform vec3 u_texture_offset;        // camera position modulo the textures' period (200 m)
uniform float u_sea_level;            // the shore band of the renderer
uniform float u_snow_height;
uniform float u_water_level;          // the generator's sea level: water fills below it
uniform float u_water_drawn;          // 1: terrain_water draws the sea over this; no tint here
uniform float u_sand_max_slope, u_sand_depth;
uniform vec2 u_edge_fade;             // Chebyshev distance where the fade to the sky starts, ends
uniform vec2 u_far_fade;              // the same in distance, before the far plane

out vec4 frag_color;

const vec3 WATER_SHALLOW = vec3(0.16, 0.36, 0.40);
const vec3 WATER_DEEP = vec3(0.05, 0.16, 0.28);

const float TEXTURE_FAR = 400.0;      // metres: beyond, an 8 m texture repeat is a few pixels
const float LAKE_SHORE_METRES = 0.5;  // depth over which a far lake fades in from its waterline

// A far lake over the lit ground `bed` (water.frag's optics without its maps: from a hundred
// metres off, waves are below a pixel). The bed is seen through the water along the view ray,
// refraction bending it to the vertical inside (Snell), Beer–Lambert taking its light and the
// water body's scatter replacing it; a Schlick Fresnel term blends in the sky mirrored by a flat
// surface; the shore fades in over LAKE_SHORE_METRES of depth, as the near water's does.
vec3 far_lake(vec3 bed, float depth, vec3 view_dir) {
    float cos_i = max(-view_dir.y, 0.0);
    float sin_t = sqrt(1.0 - cos_i * cos_i) / WATER_IOR;
    float thickness = depth / sqrt(1.0 - sin_t * sin_t);
    vec3 transmittance = exp(-WATER_EXTINCTION * thickness);
    vec3 refracted = bed * transmittance + water_body_color() * (1.0 - transmittance);
    vec3 reflected = sky_color(reflect(view_dir, vec3(0.0, 1.0, 0.0)));
    vec3 water = mix(refracted, reflected, water_fresnel(cos_i));
    return mix(bed, water, smoothstep(0.0, LAKE_SHORE_METRES, depth));
}

// 000 §6's triplanar blend with weights w = |n_i|^8 / Σ|n_j|^8, read along the pixel's two
// largest projections as terrain.frag does (materials.glsl's pick_two_of_three), the base mixed
// with itself at 25 m as terrain.frag does; far away the material's mean colour, what its
// mipmaps tend to anyway, for no fetch. No normal map or detail layer: at the clipmap's
// distances they average out (the detail to 1, the slopes to 0).
float base_shade(float layer, vec2 uv, float coarse) {
    float s = texture(u_materials, vec3(uv * u_texture_scale, layer)).r;
    // On a uniform: llvmpipe skips only such branches (the low quality saves the fetch).
    if (u_scale_blend > 0.0) s = mix(s, texture(u_materials, vec3(uv * u_texture_scale2, layer)).r, coarse);
    return s;
}

vec3 material(float layer, vec3 tint, vec3 mean, vec3 position, pick axes, float far, float coarse) {
    if (far >= 1.0) return mean;
    float c = axes.weight.x * base_shade(layer, projected(position, axes.index.x), coarse)
            + axes.weight.y * base_shade(layer, projected(position, axes.index.y), coarse);
    return mix(tint * c, mean, far);
}

// The bands of terrain.frag's bedrock tint: wet near the sea, grass on flat ground, bare rock
// higher up and on steep faces, snow on top.
vec3 rock_bands(vec3 rock, float height, float slope_degrees) {
    vec3 grass = rock * vec3(0.55, 0.85, 0.45);
    float flat_enough = 1.0 - smoothstep(28.0, 40.0, slope_degrees);
    float above_shore = smoothstep(u_sea_level + 0.5, u_sea_level + 3.0, height);
    vec3 c = mix(rock * 0.7, rock, above_shore);
    c = mix(c, grass, flat_enough * above_shore * (1.0 - smoothstep(u_snow_height - 40.0, u_snow_height - 10.0, height)));
    float snow = smoothstep(u_snow_height - 10.0, u_snow_height + 10.0, height) * (1.0 - smoothstep(35.0, 50.0, slope_degrees));
    return mix(c, vec3(0.92, 0.94, 0.97), snow);
}

void main() {
    vec2 p = v_relative_position.xz;

    vec3 n = normalize(v_normal);
    vec3 texture_position = v_relative_position + u_texture_offset;
    float distance = length(v_relative_position);
    float far = smoothstep(0.7 * TEXTURE_FAR, TEXTURE_FAR, distance);
    pick axes = pick_two_of_three(triplanar_weights(n));
    float slope = (1.0 - clamp(n.y, 0.0, 1.0)) * 90.0;
    // The macro layer where textures are (beyond, the means show no repeats to break up), for
    // a fetch saved per pixel on most of the far terrain.
    vec4 macro = far < 1.0 ? macro_sample(texture_position) : vec4(0.5, 0.5, 0.0, 1.0);
    macro.rg = mix(macro.rg, vec2(0.5), far);
    float coarse = macro_coarse_share(macro);
    vec3 albedo = rock_bands(material(0.0, u_material_tints[0], u_bedrock_mean, texture_position, axes, far, coarse), v_height, slope);
    // Sand: the generator lays sand_depth·(1 − tan/sand_max_slope) metres of it per column, by
    // the slope of the rough 1 m ground, so seen from afar it covers a share of the ground that
    // falls with the smooth slope drawn here. Measured on generated chunks (seed 42, defaults:
    // share of columns with a metre of sand on top, by the slope over 4 m): 0.64 on the flat,
    // 0.44 at 0.125, 0.22 at 0.225, 0.15 at 0.325, about 0.1 from 0.45; this fits within 0.08.
    float tangent = sqrt(max(1.0 - n.y * n.y, 0.0)) / max(n.y, 0.05);
    float sand = u_sand_max_slope > 0.0 && u_sand_depth > 0.0
               ? 0.1 + 0.55 * (1.0 - smoothstep(0.0, 1.33 * u_sand_max_slope, tangent)) : 0.0;
    if (sand > 0.0) albedo = mix(albedo, material(1.0, u_material_tints[1], u_sand_mean, texture_position, axes, far, coarse), sand);
    // The macro variation, as on the meshes, so the near-far seam keeps matching.
    albedo *= macro_tint(macro);
    // The sea: the surface stays on the ground (the meshes' sea bed meets it at the hole), and
    // ground under water takes the water's colour, deeper blue with depth, lit as a flat surface.
    float depth = u_water_level - v_height;
    if (depth > 0.0 && u_water_drawn == 0.0) {
        float cover = 1.0 - exp(-depth / 3.0);
        albedo = mix(albedo, mix(WATER_SHALLOW, WATER_DEEP, 1.0 - exp(-depth / 25.0)), cover);
        n = normalize(mix(n, vec3(0.0, 1.0, 0.0), cover));
    }
    vec3 color = light_surface_shadowed(albedo, n, shadow_visibility(v_relative_position, n));
    if (v_lake_depth > 0.0) color = far_lake(color, v_lake_depth, v_relative_position / max(distance, 1e-4));
    color = apply_fog(color, v_relative_position);
    // 002 §4.4: the end of the world melts into the sky seen in the same direction.
    float edge = max(smoothstep(u_edge_fade.x, u_edge_fade.y, max(abs(p.x), abs(p.y))),
                     smoothstep(u_far_fade.x, u_far_fade.y, distance));
    if (edge > 0.0) color = mix(color, sky_color(v_relative_position / max(distance, 1e-4)), edge);
    frag_color = vec4(color, 1.0);
}
