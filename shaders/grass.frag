#version 450 core
// grass.frag — the blade texture alpha-tested, times the tuft's light (grass_cull.comp lit it
// with the ground's normal), darker at the root, then its fog.

in vec2 v_uv;
in vec3 v_light;
in vec4 v_fog;

uniform sampler2D u_blades;

out vec4 frag_color;

void main() {
    vec4 blade = texture(u_blades, v_uv);
    if (blade.a < 0.5) discard;
    vec3 color = blade.rgb * v_light * (0.75 + 0.25 * v_uv.y);
    frag_color = vec4(mix(color, v_fog.rgb, v_fog.a), 1.0);
}
