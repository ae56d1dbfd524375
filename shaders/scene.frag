#version 450 core
// scene.frag — the reference scene's surfaces: a lit, coloured mesh, or the ground with a grid.

#include "common.glsl"

in vec3 v_world_position;
in vec3 v_normal;

uniform vec3 u_albedo;
uniform int u_grid;                // 1: draw metre grid lines on the ground

out vec4 frag_color;

// Antialiased lines every metre (thicker every ten), from screen-space derivatives.
float grid_lines(vec2 position) {
    vec2 cell = abs(fract(position - 0.5) - 0.5) / fwidth(position);
    float fine = 1.0 - clamp(min(cell.x, cell.y), 0.0, 1.0);
    vec2 coarse_position = position / 10.0;
    vec2 coarse_cell = abs(fract(coarse_position - 0.5) - 0.5) / fwidth(coarse_position);
    float coarse = 1.0 - clamp(min(coarse_cell.x, coarse_cell.y) * 0.5, 0.0, 1.0);
    return max(fine * 0.6, coarse);
}

void main() {
    vec3 normal = normalize(v_normal);
    vec3 albedo = u_albedo;
    if (u_grid == 1) albedo = mix(albedo, vec3(0.08), grid_lines(v_world_position.xz));
    vec3 color = light_surface(albedo, normal);
    frag_color = vec4(apply_fog(color, v_world_position), 1.0);
}
