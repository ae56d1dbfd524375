#version 450 core
// water_under.frag — the water fog over the whole frame when the camera is under water: dense
// exponential fog of the water's colour over the distance to what each pixel shows (the frame's
// depth), cut short by the surface above where the ray reaches it first. Drawn with sky.vert's
// full-screen triangle, blended over the frame by its alpha.

#include "common.glsl"
#include "water.glsl"

in vec2 v_ndc;
uniform float u_surface_above;     // the surface's height over the camera, metres (> 0)
uniform float u_water_density;     // per metre
out vec4 frag_color;

void main() {
    vec2 uv = v_ndc * 0.5 + 0.5;
    vec4 far = u_inverse_view_projection * vec4(v_ndc, 1.0, 1.0);
    vec3 direction = normalize(far.xyz / far.w);
    float distance = scene_distance(uv);
    if (direction.y > 1e-4) distance = min(distance, u_surface_above / direction.y);
    float fog = 1.0 - exp(-distance * u_water_density);
    vec3 light = WATER_FOG * (0.35 + 0.65 * max(u_sun_direction.y, 0.0));
    frag_color = vec4(light, fog);
}
