#version 450 core
// grass.frag — the blade texture alpha-tested, lit with the ground's normal (so far tufts take
// the ground's shading and melt into its grass tint), darker at the root, then fogged.

#include "common.glsl"

in vec2 v_uv;
in vec3 v_relative_position;
in vec3 v_normal;
in vec3 v_tint;

uniform sampler2D u_blades;

out vec4 frag_color;

void main() {
    vec4 blade = texture(u_blades, v_uv);
    if (blade.a < 0.5) discard;
    vec3 albedo = blade.rgb * v_tint * (0.75 + 0.25 * v_uv.y);
    vec3 color = light_surface(albedo, normalize(v_normal));
    frag_color = vec4(apply_fog(color, v_relative_position), 1.0);
}
