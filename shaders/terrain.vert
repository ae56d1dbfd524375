#version 450 core
// terrain.vert — terrain meshes, drawn camera-relative: positions arrive relative to their mesh's
// origin, and u_offset (mesh origin − camera, subtracted in double precision on the CPU) keeps
// every float small however far from the world's origin the camera is.

#include "materials.glsl"

layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec4 a_weights;      // bedrock, sand, rocks, water (unorm8)
layout(location = 3) in float a_occlusion;   // ambient occlusion from the mesher, 0 = open sky

uniform mat4 u_view_projection;              // camera at the origin
uniform vec3 u_offset;                       // mesh origin − camera position
uniform vec3 u_texture_offset;               // mesh origin modulo the texture period
uniform float u_mesh_y;                      // mesh origin's world height (bands are absolute)
uniform vec4 u_clip_plane;                   // camera-relative: keeps dot((p, 1), plane) ≥ 0;
                                             // all zero = nothing clipped (water's passes)

out vec3 v_relative_position;                // to the camera
out vec3 v_texture_position;                 // for the triplanar projections
out vec3 v_normal;
out vec4 v_weights;
out float v_openness;
out float v_height;
out vec4 v_macro;                            // the macro layer here (materials.glsl)

void main() {
    vec3 relative = a_position + u_offset;
    v_relative_position = relative;
    v_texture_position = a_position + u_texture_offset;
    v_normal = a_normal;
    v_weights = a_weights;
    v_openness = 1.0 - a_occlusion;
    v_height = a_position.y + u_mesh_y;
    v_macro = macro_sample(v_texture_position);
    gl_ClipDistance[0] = dot(vec4(relative, 1.0), u_clip_plane);
    gl_Position = u_view_projection * vec4(relative, 1.0);
}
