#version 450 core
// sky.frag — the sky seen along each pixel's view ray: gradient and sun (common.glsl), and a
// layer of procedural clouds that drifts with time (sky.glsl).

#include "common.glsl"
#include "sky.glsl"

in vec2 v_ndc;
uniform mat4 u_inverse_view_projection;
out vec4 frag_color;

void main() {
    vec4 far = u_inverse_view_projection * vec4(v_ndc, 1.0, 1.0);
    vec3 direction = normalize(far.xyz / far.w - u_camera_position);
    frag_color = vec4(sky_with_clouds(direction, 5), 1.0);
}
