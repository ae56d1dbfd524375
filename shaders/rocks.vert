#version 450 core
// rocks.vert — the frame's rocks as one batch (rocks_render.c): each vertex already placed by the
// CPU, relative to the camera (the seed less the camera subtracted in double precision, so every
// float stays small wherever the camera is; the rock's scale, tile size × the fade past range,
// shrinks a far rock into its seed rather than cutting it off), with its rock's tint.

layout(location = 0) in vec3 a_position;     // metres from the camera
layout(location = 1) in vec3 a_local;        // tile units from the rock's seed
layout(location = 2) in vec3 a_normal;       // snorm8
layout(location = 3) in vec3 a_tint;         // unorm8 albedo

uniform mat4 u_view_projection;              // camera at the origin

out vec3 v_relative_position;                // to the camera
out vec3 v_normal;
out vec3 v_tint;
out vec3 v_local;                            // tile units from the seed: the grain's coordinates

void main() {
    v_relative_position = a_position;
    v_normal = normalize(a_normal);
    v_tint = a_tint;
    v_local = a_local * 3.0;
    gl_Position = u_view_projection * vec4(a_position, 1.0);
}
