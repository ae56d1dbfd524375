#version 450 core
// grass.vert — one tuft per instance, shaped, lit and fogged by grass_cull.comp: two crossed
// quads, four corners each (an indexed draw, so each corner is shaded once). No vertex buffer:
// the corners come from the culling pass's buffer, roots camera-relative.

layout(std430, binding = 0) readonly buffer Visible { vec4 visible[]; };   // 5 per tuft

uniform mat4 u_view_projection;

out vec2 v_uv;                     // across the blade texture; y 0 at the root, 1 at the top
out vec3 v_light;                  // the tuft's colour times the light on its ground
out vec4 v_fog;                    // fog colour, and how much of it

void main() {
    int tuft = 5 * gl_InstanceID;
    vec4 root = visible[tuft], side0 = visible[tuft + 1], side1 = visible[tuft + 2], top = visible[tuft + 3];
    int corner = gl_VertexID & 3;                       // 0, 1 at the root; 2, 3 at the top
    vec3 side = gl_VertexID < 4 ? side0.xyz : side1.xyz;
    vec3 position = root.xyz + side * (float(corner & 1) * 2.0 - 1.0) + (corner >= 2 ? top.xyz : vec3(0.0));
    v_uv = vec2(float(corner & 1), corner >= 2 ? 1.0 : 0.0);
    v_light = vec3(side0.w, side1.w, top.w);
    v_fog = vec4(visible[tuft + 4].rgb, root.w);
    gl_Position = u_view_projection * vec4(position, 1.0);
}
