#version 450 core
// rocks.frag — stone: the instance's tint, a grain of value noise in the rock's own frame (so
// it moves with the rock, and the same rock mesh looks different under each tint), a darker
// underside where rocks rest on each other, then the shared sun, sky ambient and fog.

#include "common.glsl"

in vec3 v_relative_position;
in vec3 v_normal;
in vec3 v_tint;
in vec3 v_local;

out vec4 frag_color;

float hash31(vec3 p) {
    p = fract(p * 0.1031);
    p += dot(p, p.yzx + 33.33);
    return fract((p.x + p.y) * p.z);
}

float value_noise(vec3 p) {
    vec3 i = floor(p), f = fract(p);
    f = f * f * (3.0 - 2.0 * f);
    float n000 = hash31(i), n100 = hash31(i + vec3(1, 0, 0));
    float n010 = hash31(i + vec3(0, 1, 0)), n110 = hash31(i + vec3(1, 1, 0));
    float n001 = hash31(i + vec3(0, 0, 1)), n101 = hash31(i + vec3(1, 0, 1));
    float n011 = hash31(i + vec3(0, 1, 1)), n111 = hash31(i + vec3(1, 1, 1));
    return mix(mix(mix(n000, n100, f.x), mix(n010, n110, f.x), f.y),
               mix(mix(n001, n101, f.x), mix(n011, n111, f.x), f.y), f.z);
}

void main() {
    vec3 normal = normalize(v_normal);
    float grain = value_noise(v_local * 4.0) * 0.6 + value_noise(v_local * 11.0) * 0.4;
    vec3 albedo = v_tint * (0.78 + 0.35 * grain);
    float rest = 0.55 + 0.45 * clamp(normal.y * 0.5 + 0.6, 0.0, 1.0);   // undersides in the pile's shade
    vec3 color = light_surface(albedo, normal) * rest;
    frag_color = vec4(apply_fog(color, u_camera_position + v_relative_position), 1.0);
}
