#version 450 core
// grass.vert — one tuft per instance, shaped by grass_cull.comp: two crossed quads, four corners
// each (an indexed draw, so each corner is shaded once). No vertex buffer: the corners come from
// the culling pass's buffer, roots camera-relative.

layout(std430, binding = 0) readonly buffer Visible { vec4 visible[]; };   // 4 per tuft

uniform mat4 u_view_projection;

out vec2 v_uv;                     // across the blade texture; y 0 at the root, 1 at the top
out vec3 v_relative_position;
out vec3 v_normal;
out vec3 v_tint;

void main() {
    int tuft = 4 * gl_InstanceID;
    vec4 root = visible[tuft], side0 = visible[tuft + 1], side1 = visible[tuft + 2], top = visible[tuft + 3];
    int corner = gl_VertexID & 3;                       // 0, 1 at the root; 2, 3 at the top
    vec3 side = gl_VertexID < 4 ? side0.xyz : side1.xyz;
    vec3 position = root.xyz + side * (float(corner & 1) * 2.0 - 1.0) + (corner >= 2 ? top.xyz : vec3(0.0));
    v_uv = vec2(float(corner & 1), corner >= 2 ? 1.0 : 0.0);
    v_relative_position = position;
    v_normal = vec3(side0.w, side1.w, top.w);
    v_tint = unpackUnorm4x8(floatBitsToUint(root.w)).rgb * 1.2;
    gl_Position = u_view_projection * vec4(position, 1.0);
}
