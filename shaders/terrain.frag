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
// geometric normal in a whiteout blend, and the three are mixed with the triplanar weights. The
// macro layer (200 m, read per vertex in terrain.vert) scales brightness and hue. Fetches: 12
// base (4 materials × 3 projections: llvmpipe runs every branch), +3 at 25 m, +3 detail; the
// low quality (u_scale_blend = 0, u_detail_distance = 0) skips the last six.

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

// 000 §6: weights |n_i|^p / Σ|n_j|^p, i.e. each axis' share of ‖n‖_p^p, with p = 8.
vec3 triplanar_weights(vec3 n) {
    vec3 a = abs(n);
    vec3 w = a * a; w *= w; w *= w;           // |n|^8
    return w / max(w.x + w.y + w.z, 1e-6);
}

// One projection of one material: its shade, and its tangent slopes added to `slope`.
float projection_shade(float layer, vec2 uv, inout vec2 slope) {
    vec3 base = texture(u_materials, vec3(uv * u_texture_scale, layer)).rgb;
    slope += base.gb * 2.0 - 1.0;
    return base.r;
}

// One material's shade over the projections; its tangent slopes, times its weight, are added to
// the projections' (each in its texture axes: x reads (z, y), y reads (x, z), z reads (x, y)).
float material_shade(float layer, float weight, vec3 blend, inout vec2 slope_x, inout vec2 slope_y, inout vec2 slope_z) {
    vec3 p = v_texture_position;
    float shade = 0.0;
    vec2 slope;
    if (blend.x > 0.01) { slope = vec2(0.0); shade += blend.x * projection_shade(layer, p.zy, slope); slope_x += weight * slope; }
    if (blend.y > 0.01) { slope = vec2(0.0); shade += blend.y * projection_shade(layer, p.xz, slope); slope_y += weight * slope; }
    if (blend.z > 0.01) { slope = vec2(0.0); shade += blend.z * projection_shade(layer, p.xy, slope); slope_z += weight * slope; }
    return shade;
}

// llvmpipe runs both sides of a branch that differs between pixels, fetches included; only a
// branch on a uniform is really skipped. So what the quality setting leaves out sits under
// uniform conditions, and the extra layers are read once per projection for the dominant
// material (`layer`), not once per material: three fetches each.

// The 25 m sample of the dominant material as a factor with a mean of 1 (its shade over its
// mean shade), mixed in by `coarse`: a pattern that never lines up with the 8 m repeats.
float coarse_factor(float layer, vec3 blend, float coarse) {
    vec3 p = v_texture_position * u_texture_scale2;
    float shade = blend.x * texture(u_materials, vec3(p.zy, layer)).r + blend.y * texture(u_materials, vec3(p.xz, layer)).r
                + blend.z * texture(u_materials, vec3(p.xy, layer)).r;
    return mix(1.0, shade / u_mean_shades[int(layer)], coarse);
}

// The 1 m detail of the dominant material: its multiplier (mean 1), faded by `detail`, and its
// slopes added to the projections' (UDN: the slopes of two height maps add).
float detail_factor(float layer, vec3 blend, float detail, inout vec2 slope_x, inout vec2 slope_y, inout vec2 slope_z) {
    vec3 p = v_texture_position * u_detail_scale;
    vec3 dx = texture(u_detail, vec3(p.zy, layer)).rgb, dy = texture(u_detail, vec3(p.xz, layer)).rgb;
    vec3 dz = texture(u_detail, vec3(p.xy, layer)).rgb;
    slope_x += (dx.gb * 2.0 - 1.0) * detail;
    slope_y += (dy.gb * 2.0 - 1.0) * detail;
    slope_z += (dz.gb * 2.0 - 1.0) * detail;
    return mix(1.0, 2.0 * (blend.x * dx.r + blend.y * dy.r + blend.z * dz.r), detail);
}

// Triplanar normal mapping, whiteout blend per axis: projection x reads (z, y), y reads (x, z),
// z reads (x, y). Each projection's slopes are added to the geometric normal's components in its
// texture axes and the axis' own component is the normal's, sign included, so faces looking down
// an axis are lit as those looking up. The coordinates are world positions, never mirrored, so a
// height map's slope points the same world way on both faces of an axis: no flip is needed.
vec3 triplanar_normal(vec3 n, vec3 blend, vec2 slope_x, vec2 slope_y, vec2 slope_z) {
    vec3 along_x = vec3(n.x, n.y + slope_x.y, n.z + slope_x.x);
    vec3 along_y = vec3(n.x + slope_y.x, n.y, n.z + slope_y.y);
    vec3 along_z = vec3(n.x + slope_z.x, n.y + slope_z.y, n.z);
    return normalize(along_x * blend.x + along_y * blend.y + along_z * blend.z);
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
    vec3 blend = triplanar_weights(n);
    vec4 w = v_weights / max(dot(v_weights, vec4(1.0)), 1e-4);
    float slope = (1.0 - clamp(n.y, 0.0, 1.0)) * 90.0;
    float distance = length(v_relative_position);
    vec2 slope_x = vec2(0.0), slope_y = vec2(0.0), slope_z = vec2(0.0);
    vec3 albedo = vec3(0.0);
    if (w.x > 0.01) albedo += w.x * bedrock_tint(u_material_tints[0] * material_shade(0.0, w.x, blend, slope_x, slope_y, slope_z), v_height, slope);
    if (w.y > 0.01) albedo += w.y * u_material_tints[1] * material_shade(1.0, w.y, blend, slope_x, slope_y, slope_z);
    if (w.z > 0.01) albedo += w.z * u_material_tints[2] * material_shade(2.0, w.z, blend, slope_x, slope_y, slope_z);
    if (w.w > 0.01) albedo += w.w * u_material_tints[3] * material_shade(3.0, w.w, blend, slope_x, slope_y, slope_z);
    float dominant = w.x >= max(w.y, max(w.z, w.w)) ? 0.0 : w.y >= max(w.z, w.w) ? 1.0 : w.z >= w.w ? 2.0 : 3.0;
    // The 25 m factor fades in from 24 to 48 m: nearer, a screen holds too little ground for
    // the 8 m repeat to show.
    if (u_scale_blend > 0.0)
        albedo *= coarse_factor(dominant, blend, macro_coarse_share(v_macro) * smoothstep(24.0, 48.0, distance));
    // The detail fades out over the second half of its reach: further away its 1 m repeat is a
    // few pixels, averaged by the mipmaps to 1 anyway.
    if (u_detail_distance > 0.0)
        albedo *= detail_factor(dominant, blend, 1.0 - smoothstep(0.5 * u_detail_distance, u_detail_distance, distance),
                                slope_x, slope_y, slope_z);
    albedo *= macro_tint(v_macro);
    vec3 color = light_surface_open(albedo, triplanar_normal(n, blend, slope_x, slope_y, slope_z),
                                    mix(1.0, v_openness, u_occlusion), shadow_visibility(v_relative_position, n));
    // common.glsl's fog works in world space around u_camera_position; here the camera is the
    // origin, so pass relative positions with u_camera_position = 0.
    frag_color = vec4(apply_fog(color, v_relative_position), 1.0);
}
