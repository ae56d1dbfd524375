#version 450 core
// water.vert — one flat water surface: a quad from gl_VertexID (two triangles, no attributes),
// camera-relative like the terrain: u_corner is the quad's corner less the camera (subtracted in
// double precision on the CPU), so every float stays small wherever the camera is.

uniform mat4 u_view_projection;    // camera at the origin
uniform vec3 u_corner;             // the quad's (min x, height, min z) − camera
uniform vec2 u_extent;             // metres along x and z
uniform float u_cell;              // metres per cell of the plane's row mask (lakes)

out vec3 v_relative_position;      // to the camera
out vec2 v_cell;                   // cells from the quad's corner, x and z

void main() {
    const vec2 corners[6] = vec2[6](vec2(0, 0), vec2(1, 0), vec2(1, 1), vec2(0, 0), vec2(1, 1), vec2(0, 1));
    vec2 corner = corners[gl_VertexID];
    vec2 local = corner * u_extent;
    v_relative_position = vec3(u_corner.x + local.x, u_corner.y, u_corner.z + local.y);
    v_cell = local / u_cell;
    gl_Position = u_view_projection * vec4(v_relative_position, 1.0);
}
