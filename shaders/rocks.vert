#version 450 core
// rocks.vert — one rock mesh of the tile set per draw command, its instances from a buffer
// (rocks_render.c). Vertices arrive relative to the rock's seed point in tile units; each instance
// gives the seed's position less the camera (subtracted in double precision on the CPU, so every
// float stays small wherever the camera is) and the scale: tile size × the fade past range,
// which shrinks a far rock into its seed rather than cutting it off.

layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;       // snorm8
layout(location = 2) in vec4 a_instance;     // seed − camera (metres), scale
layout(location = 3) in vec4 a_tint;         // albedo (rgb); w is the CPU's bucket id

uniform mat4 u_view_projection;              // camera at the origin

out vec3 v_relative_position;                // to the camera
out vec3 v_normal;
out vec3 v_tint;
out vec3 v_local;                            // tile units from the seed: the grain's coordinates

void main() {
    vec3 relative = a_instance.xyz + a_position * a_instance.w;
    v_relative_position = relative;
    v_normal = normalize(a_normal);
    v_tint = a_tint.rgb;
    v_local = a_position * 3.0;
    gl_Position = u_view_projection * vec4(relative, 1.0);
}
