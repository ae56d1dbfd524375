#version 450 core
// terrain.frag — triplanar texturing with blend exponent p = 8 (000 §6), materials mixed by the
// per-vertex weights of visible material (000 §6), and bedrock tinted by height bands and slope
// (002 §4.1: α = (1 − n_y)·90°), then the sun, sky ambient and distance fog of common.glsl.
//
// Materials (materials.glsl, textures from terrain_textures.c): per projection the 8 m base is
// mixed with itself at 25 m (share from the macro layer, from 24–48 m out), then, within
// u_detail_distance, a 1 m detail layer multiplies the shade (mean 1, so a region's colour does
// not change) and adds its slopes to the base's normal map (UDN). The summed tangent slopes of each projection meet the
// geometric normal in a whiteout blend, and the three are mixed with the triplanar weights. The
// macro layer (200 m) scales brightness and hue. Fetches per material and projection: 1 base, +1
// for the 25 m sample past 24 m, +1 detail within u_detail_distance; +1 per fragment for the
// macro layer.

#include "common.glsl"
#include "materials.glsl"

in vec3 v_relative_position;
in vec3 v_texture_position;
in vec3 v_normal;
in vec4 v_weights;
in float v_height;

uniform float u_sea_level;
uniform float u_snow_height;
uniform float u_detail_scale;                // detail repeats per metre (1 / 1 m)
uniform float u_detail_distance;             // metres; 0 = no detail layer

out vec4 frag_color;

// 000 §6: weights |n_i|^p / Σ|n_j|^p, i.e. each axis' share of ‖n‖_p^p, with p = 8.
vec3 triplanar_weights(vec3 n) {
    vec3 a = abs(n);
    vec3 w = a * a; w *= w; w *= w;           // |n|^8
    return w / max(w.x + w.y + w.z, 1e-6);
}

// One projection of one material: its shade (times the detail's multiplier), and its tangent
// slopes added to `slope`. The 25 m sample only where `coarse` > 0 (away from the camera, where
// repeats show) and the detail only where `detail` > 0: llvmpipe skips a fetch no pixel of a
// block needs, and a fetch costs it more than anything else here.
float projection_shade(float layer, vec2 uv, float detail, float coarse, inout vec2 slope) {
    vec3 base = texture(u_materials, vec3(uv * u_texture_scale, layer)).rgb;
    if (coarse > 0.0) base = mix(base, texture(u_materials, vec3(uv * u_texture_scale2, layer)).rgb, coarse);
    float s = base.r;
    slope += base.gb * 2.0 - 1.0;
    if (detail > 0.0) {
        vec3 d = texture(u_detail, vec3(uv * u_detail_scale, layer)).rgb;
        s *= mix(1.0, d.r * 2.0, detail);
        slope += (d.gb * 2.0 - 1.0) * detail;   // UDN: the slopes of two height maps add
    }
    return s;
}

// One material's shade over the projections; its tangent slopes, times its weight, are added to
// `slopes` (per projection, in that projection's texture axes: x reads (z, y), y reads (x, z),
// z reads (x, y)).
float material_shade(float layer, float weight, vec3 blend, float detail, float coarse,
                     inout vec2 slope_x, inout vec2 slope_y, inout vec2 slope_z) {
    vec3 p = v_texture_position;
    float shade = 0.0;
    vec2 slope;
    if (blend.x > 0.01) { slope = vec2(0.0); shade += blend.x * projection_shade(layer, p.zy, detail, coarse, slope); slope_x += weight * slope; }
    if (blend.y > 0.01) { slope = vec2(0.0); shade += blend.y * projection_shade(layer, p.xz, detail, coarse, slope); slope_y += weight * slope; }
    if (blend.z > 0.01) { slope = vec2(0.0); shade += blend.z * projection_shade(layer, p.xy, detail, coarse, slope); slope_z += weight * slope; }
    return shade;
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

void main() {
    vec3 n = normalize(v_normal);
    vec3 blend = triplanar_weights(n);
    vec4 w = v_weights / max(dot(v_weights, vec4(1.0)), 1e-4);
    float slope = (1.0 - clamp(n.y, 0.0, 1.0)) * 90.0;
    // The detail fades out over the second half of its reach: further away its 1 m repeat is a
    // few pixels, averaged by the mipmaps to 1 anyway, and its fetches are saved.
    float distance = length(v_relative_position);
    float detail = u_detail_distance > 0.0 ? 1.0 - smoothstep(0.5 * u_detail_distance, u_detail_distance, distance) : 0.0;
    vec4 macro = macro_sample(v_texture_position);
    // The 25 m sample fades in from 24 to 48 m: nearer, a screen holds too little ground for the
    // 8 m repeat to show, and the fetch is saved.
    float coarse = macro_coarse_share(macro) * smoothstep(24.0, 48.0, distance);
    vec2 slope_x = vec2(0.0), slope_y = vec2(0.0), slope_z = vec2(0.0);
    vec3 albedo = vec3(0.0);
    if (w.x > 0.01) albedo += w.x * bedrock_tint(u_material_tints[0] * material_shade(0.0, w.x, blend, detail, coarse, slope_x, slope_y, slope_z), v_height, slope);
    if (w.y > 0.01) albedo += w.y * u_material_tints[1] * material_shade(1.0, w.y, blend, detail, coarse, slope_x, slope_y, slope_z);
    if (w.z > 0.01) albedo += w.z * u_material_tints[2] * material_shade(2.0, w.z, blend, detail, coarse, slope_x, slope_y, slope_z);
    if (w.w > 0.01) albedo += w.w * u_material_tints[3] * material_shade(3.0, w.w, blend, detail, coarse, slope_x, slope_y, slope_z);
    albedo *= macro_tint(macro);
    vec3 color = light_surface(albedo, triplanar_normal(n, blend, slope_x, slope_y, slope_z));
    // common.glsl's fog works in world space around u_camera_position; here the camera is the
    // origin, so pass relative positions with u_camera_position = 0.
    frag_color = vec4(apply_fog(color, v_relative_position), 1.0);
}
