#version 450 core
// clipmap.vert — one level of the far terrain's geometry clipmap (002 §3.2; Losasso & Hoppe
// 2004). The grid of (u_cells + 1)² vertices has no attributes: (i, k) comes from gl_VertexID.
// Heights come from this level's layer of u_heights, a toroidal array: grid point (i, k) sits at
// texel (i mod u_size, k mod u_size), so the indices are wrapped here and read with texelFetch.
// Near the level's border each vertex morphs to the coarser level's triangles (the formula of
// terrain__clipmap_morph in terrain_internal.h, which the CPU tests check; keep the two alike).
// Everything arrives camera-relative: positions are small wherever the camera is.

uniform mat4 u_view_projection;    // camera at the origin
uniform sampler2DArray u_heights;  // RGBA32F, one layer per level: height, the unit normal's x
                                   // and z, the lake level (−1e30: none)
uniform int u_size;                // texels along each side of a layer (toroidal period)
uniform int u_cells;               // cells along each side of a level
uniform int u_layer, u_coarse_layer;   // this level's layer, the coarser level's (−1: none)
uniform ivec2 u_start;             // texel of vertex (0, 0) in this layer
uniform ivec2 u_coarse_start;      // texel of the coarser level's vertex at vertex (0, 0)
uniform ivec2 u_offset;            // vertex (0, 0) from the anchor, in this level's spacings
uniform vec2 u_anchor;             // the anchor (a vertex of every level) − camera, x and z
uniform float u_spacing;           // metres between this level's vertices
uniform float u_camera_y;
uniform vec2 u_morph;              // where the morph starts (metres from the centre), 1 / width
uniform vec2 u_morph_centre;       // the camera of the clipmap's last update, camera-relative
const int MAX_HOLES = 8;           // TERRAIN_CLIPMAP_MAX_HOLES: one per viewer's rings
uniform vec4 u_holes[MAX_HOLES];   // the holes, camera-relative: min x, min z, max x, max z
uniform int u_hole_count;          // how many of them are set
uniform float u_hole_band, u_hole_depth;
uniform int u_seam_exact;          // 1: the heights are the chunks' where they are (a world)
uniform vec4 u_clip_plane;         // camera-relative: keeps dot((p, 1), plane) ≥ 0; zero = off

out vec3 v_relative_position;      // to the camera
out vec3 v_normal;
out float v_height;                // world height of the ground (before any sinking)
out float v_lake_depth;            // metres of lake water over the ground (≤ 0: dry land)

// The height, the normal (central differences over the level's own grid, one texel ring
// beyond the vertices kept for them) and the lake level in one read: the CPU packs them
// (packed_texel in terrain_clipmap.c), which spares four reads per vertex.
vec4 texel_at(int layer, ivec2 texel) {
    // texel is within [0, 2·u_size) (a start texel in [0, u_size) plus at most u_cells + 1):
    // one subtraction wraps it. No integer % or /: llvmpipe does those a lane at a time.
    ivec2 wrapped = texel - u_size * ivec2(greaterThanEqual(texel, ivec2(u_size)));
    return texelFetch(u_heights, ivec3(wrapped, layer), 0);
}

// The normal's y from its x and z: a height field's normals all point up.
vec3 texel_normal(vec4 texel) {
    return vec3(texel.g, sqrt(max(1.0 - texel.g * texel.g - texel.b * texel.b, 0.0)), texel.b);
}

// How deep inside a hole a camera-relative point is (≤ 0 outside).
float hole_depth_inside(vec4 hole, vec2 p) {
    return min(min(p.x - hole.x, hole.z - p.x), min(p.y - hole.y, hole.w - p.y));
}

void main() {
    // The row from a float quotient (llvmpipe divides integers a lane at a time), put right
    // if rounding left it one off: the column must come out in [0, row_length).
    int row_length = u_cells + 1;
    int row = int((float(gl_VertexID) + 0.5) / float(row_length));
    int column = gl_VertexID - row * row_length;
    int off = int(column >= row_length) - int(column < 0);
    ivec2 grid = ivec2(column - off * row_length, row + off);
    // The anchor is shared by all levels and (u_offset + grid)·u_spacing is exact, so a vertex
    // that two levels share gets the same bits in both.
    precise vec2 position = u_anchor + vec2(u_offset + grid) * u_spacing;
    ivec2 texel = u_start + grid;
    vec4 here = texel_at(u_layer, texel);
    float fine = here.r;
    vec3 normal = texel_normal(here);
    float lake = here.a;
    precise float height = fine;
    // What is drawn: the ground, or a lake's surface where its vertices stand in a lake (far
    // lakes; the near ones are WaterPlane components that terrain_water draws). It morphs as a
    // whole, so a finer border vertex lies on the coarser level's drawn edge, shore or not.
    precise float surface = max(fine, lake);
    // On a hole's border, with the chunks' heights in the texels, the vertex keeps its own
    // height whatever the morph: there the clipmap meets the chunks' meshes (002 §3.5). A crack
    // this opens against a coarser level lies in the border's plane, over the pit: ground shows
    // through it, never sky (terrain_clipmap.c, "The seam").
    // Inside a hole the surface sinks within u_hole_band of the border to u_hole_depth below
    // the ground: a pit under the volumetric chunks, whose walls are the skirt of their open
    // border (terrain_clipmap.c says why it is a pit rather than a cut-out). Where holes
    // overlap the deepest pit wins, so their union is one pit (terrain__clipmap_sink mirrors it).
    // The loop runs to the constant MAX_HOLES under a uniform test, so llvmpipe unrolls it and
    // reads u_holes at constant indices (terrain_clipmap.c binds each block only its holes).
    bool seam = false;
    float sink = 0.0;
    for (int h = 0; h < MAX_HOLES; h++) {
        if (h < u_hole_count) {
            float inside = hole_depth_inside(u_holes[h], position);
            seam = seam || (u_seam_exact != 0 && abs(inside) <= 1e-3 * u_spacing);
            sink = max(sink, inside > 0.0 ? u_hole_depth * clamp(inside / u_hole_band, 0.0, 1.0) : 0.0);
        }
    }
    if (u_coarse_layer >= 0) {
        bool border = grid.x == 0 || grid.y == 0 || grid.x == u_cells || grid.y == u_cells;
        // Measured from the camera the levels were placed for, so that the transition always
        // ends inside the level and the coarser level is unmorphed under the finer border.
        vec2 from_centre = position - u_morph_centre;
        float alpha = clamp((max(abs(from_centre.x), abs(from_centre.y)) - u_morph.x) * u_morph.y, 0.0, 1.0);
        alpha = border ? 1.0 : alpha;
        alpha = seam ? 0.0 : alpha;
        if (alpha > 0.0) {
            // The coarser triangles under the vertex: its vertex, an edge's midpoint, or the
            // midpoint of the cell's (0, 0)–(1, 1) diagonal.
            ivec2 c0 = u_coarse_start + (grid >> 1), c1 = c0 + (grid & 1);
            vec4 t0 = texel_at(u_coarse_layer, c0), t1 = texel_at(u_coarse_layer, c1);
            precise float coarse = 0.5 * (t0.r + t1.r);
            vec3 coarse_normal = texel_normal(t0) + texel_normal(t1);
            height = (1.0 - alpha) * fine + alpha * coarse;
            precise float coarse_surface = 0.5 * (max(t0.r, t0.a) + max(t1.r, t1.a));
            surface = (1.0 - alpha) * surface + alpha * coarse_surface;
            normal = mix(normal, normalize(coarse_normal), alpha);
            // A level without lakes (coarser than 8 m) averages the level away: its sentinel
            // pulls any mix far below the ground, so a lake ends at the morph's far edge.
            lake = (1.0 - alpha) * lake + alpha * 0.5 * (t0.a + t1.a);
        }
    }
    // Inside a hole the meshes draw the lake's bed and terrain_water its surface: the pit stays
    // the ground's.
    if (sink > 0.0) surface = height;
    // Clamped: a vertex out of the lake (its level the sentinel) is dry by a metre, as the shore
    // around a lake's water stands (terrain_generate.c, "Lakes"), so the waterline falls inside
    // the triangles between it and the lake's vertices.
    v_lake_depth = sink > 0.0 ? -1.0 : max(lake - height, -1.0);
    v_relative_position = vec3(position.x, surface - sink - u_camera_y, position.y);
    v_normal = normal;
    v_height = height;
    gl_ClipDistance[0] = dot(vec4(v_relative_position, 1.0), u_clip_plane);
    gl_Position = u_view_projection * vec4(v_relative_position, 1.0);
}
