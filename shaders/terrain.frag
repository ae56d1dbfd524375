#version 450 core
// terrain.frag — triplanar texturing with blend exponent p = 8 (000 §6), materials mixed by the
// per-vertex weights of visible material (000 §6), and bedrock tinted by height bands and slope
// (002 §4.1: α = (1 − n_y)·90°), then the sun, sky ambient and distance fog of common.glsl.
//
// Materials (materials.glsl, textures from terrain_textures.c): per material and projection the
// 8 m base gives a shade and tangent slopes. For the dominant material, per projection, the base
// at 25 m multiplies the albedo (over its mean, from 24–48 m out, share from the macro layer),
// and within u_detail_distance a 1 m detail layer does too (mean 1, so a region's colour does
// not change) and adds its slopes (UDN). The summed tangent slopes of each projection meet the
// geometric normal in a whiteout blend, and the projections are mixed by their weights. The
// macro layer (200 m, read per vertex in terrain.vert) scales brightness and hue. Each pixel
// reads its two largest projections and its two largest materials (materials.glsl's picks):
// fetches 4 base, +2 at 25 m, +2 detail; the low quality (u_scale_blend = 0,
// u_detail_distance = 0) skips the last four.

#include "common.glsl"
#include "materials.glsl"
#include "shadow.glsl"

in vec3 v_relative_position;
in vec3 v_texture_position;
in vec3 v_normal;
in vec4 v_weights;
in float v_openness;
in float v_height;
in vec4 v_macro;                             // per vertex: it varies over tens of metres

uniform float u_sea_level;
uniform float u_snow_height;
uniform float u_occlusion;                   // 1: light by v_openness; 0: as if all open
uniform float u_detail_scale;                // detail repeats per metre (1 / 1 m)
uniform float u_detail_distance;             // metres; 0 = no detail layer

out vec4 frag_color;

// A projection's tangent slopes added to the geometric normal's components in its texture axes
// (whiteout); the axis' own component is the normal's, sign included, so faces looking down an
// axis are lit as those looking up. The coordinates are world positions, never mirrored, so a
// height map's slope points the same world way on both faces of an axis: no flip is needed.
vec3 whiteout(vec3 n, int axis, vec2 slope) {
    return n + (axis == 0 ? vec3(0.0, slope.y, slope.x) : axis == 1 ? vec3(slope.x, 0.0, slope.y) : vec3(slope, 0.0));
}

// One material's shade over the two projections, and its tangent slopes, times its weight,
// added to each projection's.
float material_shade(float layer, float weight, pick axes, vec2 uv0, vec2 uv1, inout vec2 slope0, inout vec2 slope1) {
    vec3 a = texture(u_materials, vec3(uv0 * u_texture_scale, layer)).rgb;
    vec3 b = texture(u_materials, vec3(uv1 * u_texture_scale, layer)).rgb;
    slope0 += weight * (a.gb * 2.0 - 1.0);
    slope1 += weight * (b.gb * 2.0 - 1.0);
    return axes.weight.x * a.r + axes.weight.y * b.r;
}

// The 25 m sample of the dominant material as a factor with a mean of 1 (its shade over its
// mean shade), mixed in by `coarse`: a pattern that never lines up with the 8 m repeats.
float coarse_factor(float layer, pick axes, vec2 uv0, vec2 uv1, float coarse) {
    float shade = axes.weight.x * texture(u_materials, vec3(uv0 * u_texture_scale2, layer)).r
                + axes.weight.y * texture(u_materials, vec3(uv1 * u_texture_scale2, layer)).r;
    return mix(1.0, shade / u_mean_shades[int(layer)], coarse);
}

// The 1 m detail of the dominant material: its multiplier (mean 1), faded by `detail`, and its
// slopes added to the projections' (UDN: the slopes of two height maps add).
float detail_factor(float layer, pick axes, vec2 uv0, vec2 uv1, float detail, inout vec2 slope0, inout vec2 slope1) {
    vec3 a = texture(u_detail, vec3(uv0 * u_detail_scale, layer)).rgb, b = texture(u_detail, vec3(uv1 * u_detail_scale, layer)).rgb;
    slope0 += (a.gb * 2.0 - 1.0) * detail;
    slope1 += (b.gb * 2.0 - 1.0) * detail;
    return mix(1.0, 2.0 * (axes.weight.x * a.r + axes.weight.y * b.r), detail);
}

// 002 §4.1: bands by height (wet shore, grass, bare rock, snow), with steep slopes bare.
vec3 bedrock_tint(vec3 rock, float height, float slope_degrees) {
    vec3 grass = rock * vec3(0.55, 0.85, 0.45);
    vec3 snow = vec3(0.92, 0.94, 0.97);
    float flat_enough = 1.0 - smoothstep(28.0, 40.0, slope_degrees);
    float above_shore = smoothstep(u_sea_level + 0.5, u_sea_level + 3.0, height);
    vec3 c = mix(rock * 0.7, rock, above_shore);                       // wet near the water
    c = mix(c, grass, flat_enough * above_shore * (1.0 - smoothstep(u_snow_height - 40.0, u_snow_height - 10.0, height)));
    float snow_amount = smoothstep(u_snow_height - 10.0, u_snow_height + 10.0, height)
                      * (1.0 - smoothstep(35.0, 50.0, slope_degrees));
    return mix(c, snow, snow_amount);
}

// common.glsl's light_surface_shadowed with the mesher's openness (terrain_mesh.c): the sky
// ambient comes only through the open part of the hemisphere, and the sun a little less in
// hollows (beyond the shadow map's reach nothing else keeps it out of a cave). Openness 1 gives
// light_surface_shadowed exactly.
vec3 light_surface_open(vec3 albedo, vec3 normal, float openness, float sun_visibility) {
    float diffuse = max(dot(normal, u_sun_direction), 0.0) * mix(0.4, 1.0, openness) * sun_visibility;
    vec3 ambient = mix(GROUND_BOUNCE, SKY_ZENITH, normal.y * 0.5 + 0.5) * 0.35 * openness;
    return albedo * (SUN_COLOR * diffuse + ambient);
}

void main() {
    vec3 n = normalize(v_normal);
    pick axes = pick_two_of_three(triplanar_weights(n));
    pick materials = pick_two_of_four(v_weights);
    vec2 uv0 = projected(v_texture_position, axes.index.x), uv1 = projected(v_texture_position, axes.index.y);
    float slope = (1.0 - clamp(n.y, 0.0, 1.0)) * 90.0;
    float distance = length(v_relative_position);
    vec2 slope0 = vec2(0.0), slope1 = vec2(0.0);
    vec3 albedo = vec3(0.0);
    for (int m = 0; m < 2; m++) {
        int layer = materials.index[m];
        vec3 tinted = u_material_tints[layer] * material_shade(float(layer), materials.weight[m], axes, uv0, uv1, slope0, slope1);
        albedo += materials.weight[m] * (layer == 0 ? bedrock_tint(tinted, v_height, slope) : tinted);
    }
    float dominant = float(materials.index.x);
    // The 25 m factor fades in from 24 to 48 m: nearer, a screen holds too little ground for
    // the 8 m repeat to show.
    if (u_scale_blend > 0.0)
        albedo *= coarse_factor(dominant, axes, uv0, uv1, macro_coarse_share(v_macro) * smoothstep(24.0, 48.0, distance));
    // The detail fades out over the second half of its reach: further away its 1 m repeat is a
    // few pixels, averaged by the mipmaps to 1 anyway.
    if (u_detail_distance > 0.0)
        albedo *= detail_factor(dominant, axes, uv0, uv1, 1.0 - smoothstep(0.5 * u_detail_distance, u_detail_distance, distance),
                                slope0, slope1);
    albedo *= macro_tint(v_macro);
    vec3 normal = normalize(whiteout(n, axes.index.x, slope0) * axes.weight.x + whiteout(n, axes.index.y, slope1) * axes.weight.y);
    vec3 color = light_surface_open(albedo, normal, mix(1.0, v_openness, u_occlusion), shadow_visibility(v_relative_position, n));
    // common.glsl's fog works in world space around u_camera_position; here the camera is the
    // origin, so pass relative positions with u_camera_position = 0.
    frag_color = vec4(apply_fog(color, v_relative_position), 1.0);
}
