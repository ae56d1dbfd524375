#version 450 core
// scene.vert — meshes of the reference scene: world-space position and normal to the fragment.

layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;

uniform mat4 u_model;
uniform mat4 u_view_projection;

out vec3 v_world_position;
out vec3 v_normal;

void main() {
    vec4 world = u_model * vec4(a_position, 1.0);
    v_world_position = world.xyz;
    v_normal = mat3(u_model) * a_normal;
    gl_Position = u_view_projection * world;
}
