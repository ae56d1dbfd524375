#version 450 core
// terrain.frag — triplanar texturing with blend exponent p = 8 (000 §6), materials mixed by the
// per-vertex weights of visible material (000 §6), and bedrock tinted by height bands and slope
// (002 §4.1: α = (1 − n_y)·90°), then the sun, sky ambient and distance fog of common.glsl.

#include "common.glsl"
#include "shadow.glsl"

in vec3 v_relative_position;
in vec3 v_texture_position;
in vec3 v_normal;
in vec4 v_weights;
in float v_height;

uniform sampler2DArray u_materials;          // layers: bedrock, sand, rocks, water bed
uniform float u_texture_scale;               // texture repeats per metre
uniform float u_sea_level;
uniform float u_snow_height;

out vec4 frag_color;

// 000 §6: weights |n_i|^p / Σ|n_j|^p, i.e. each axis' share of ‖n‖_p^p, with p = 8.
vec3 triplanar_weights(vec3 n) {
    vec3 a = abs(n);
    vec3 w = a * a; w *= w; w *= w;           // |n|^8
    return w / max(w.x + w.y + w.z, 1e-6);
}

vec3 material_color(float layer, vec3 position, vec3 blend) {
    vec3 p = position * u_texture_scale;
    vec3 c = vec3(0.0);
    if (blend.x > 0.01) c += blend.x * texture(u_materials, vec3(p.zy, layer)).rgb;
    if (blend.y > 0.01) c += blend.y * texture(u_materials, vec3(p.xz, layer)).rgb;
    if (blend.z > 0.01) c += blend.z * texture(u_materials, vec3(p.xy, layer)).rgb;
    return c;
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
    vec3 albedo = vec3(0.0);
    if (w.x > 0.01) albedo += w.x * bedrock_tint(material_color(0.0, v_texture_position, blend), v_height, slope);
    if (w.y > 0.01) albedo += w.y * material_color(1.0, v_texture_position, blend);
    if (w.z > 0.01) albedo += w.z * material_color(2.0, v_texture_position, blend);
    if (w.w > 0.01) albedo += w.w * material_color(3.0, v_texture_position, blend);
    vec3 color = light_surface_shadowed(albedo, n, shadow_visibility(v_relative_position, n));
    // common.glsl's fog works in world space around u_camera_position; here the camera is the
    // origin, so pass relative positions with u_camera_position = 0.
    frag_color = vec4(apply_fog(color, v_relative_position), 1.0);
}
