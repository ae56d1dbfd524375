// water.glsl — what water.frag and water_under.frag share: the water's optics (water_optics.glsl)
// and distances read back from a depth texture of the frame.

#include "water_optics.glsl"

uniform sampler2D u_scene_depth;           // the frame's depth under the water (a copy or a pass)
uniform mat4 u_inverse_view_projection;    // of the view the frame was drawn with, camera at 0

// Metres from the camera to the frame's surface at `uv` (1e6 where only the sky was drawn).
float scene_distance(vec2 uv) {
    float depth = texture(u_scene_depth, uv).r;
    if (depth >= 1.0) return 1e6;
    vec4 p = u_inverse_view_projection * vec4(uv * 2.0 - 1.0, depth * 2.0 - 1.0, 1.0);
    return length(p.xyz / p.w);
}
