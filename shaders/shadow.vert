#version 450 core
// shadow.vert — terrain meshes into one cascade of the sun's shadow map (terrain_shadow.c):
// camera-relative like terrain.vert, through the cascade's orthographic light projection.

layout(location = 0) in vec3 a_position;

uniform mat4 u_light_projection;             // camera-relative position → the cascade's clip space
uniform vec3 u_offset;                       // mesh origin − camera position (double on the CPU)

void main() {
    gl_Position = u_light_projection * vec4(a_position + u_offset, 1.0);
}
