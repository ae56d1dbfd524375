#version 450 core
// grass_place.comp — tufts from a terrain mesh chunk's triangles (002 §3.3), one invocation per
// triangle, run twice: u_write 0 counts each triangle's tufts into counts[t]; grass_scan.comp
// turns the counts into offsets; u_write 1 writes them there. The order of the tufts is the order
// of the triangles, so the buffer is the same bytes in every run.
//
// Where 002 §3.3 draws two random barycentric coordinates per triangle, the points here come
// from a lattice of the world: cell (I, J) of 1/u_density metres holds one point, jittered by a
// hash of (I, J). A triangle takes the points that fall inside it seen from above, at their
// barycentric position on it. The same (x, z) then gets the same tuft whatever triangles the
// chunk has: coarser rings of detail and remeshing after an edit leave the grass where it was.

#include "grass.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer Vertices { uint vertex_words[]; };   // terrain_vertex, 8 words
layout(std430, binding = 1) readonly buffer Indices { uint indices[]; };
layout(std430, binding = 2) buffer Counts { uint counts[]; };
layout(std430, binding = 3) writeonly buffer Tufts { vec4 tufts[]; };           // 2 per tuft
layout(std430, binding = 4) readonly buffer Tops { float tops[]; };             // sky test, per column

uniform uint u_triangle_count;
uniform int u_write;
uniform int u_density;             // lattice cells per metre
uniform uvec2 u_origin_cell;       // the mesh origin's lattice cell (x, z), wrapped to 32 bits
uniform float u_origin_y;          // the mesh origin's world height
uniform vec2 u_tops_origin;        // mesh origin − first column of the tops grid (x, z), metres
uniform int u_tops_size;           // columns along each side of the tops grid
uniform uint u_seed;
uniform float u_slope_limit;       // degrees
uniform float u_sea_level;
uniform float u_snow_height;

const float SKY_MARGIN = 1.5;      // metres of solid allowed above a tuft (the field's smoothing)

vec3 vertex_position(uint v) {
    return vec3(uintBitsToFloat(vertex_words[v * 8u]), uintBitsToFloat(vertex_words[v * 8u + 1u]),
                uintBitsToFloat(vertex_words[v * 8u + 2u]));
}
vec3 vertex_normal(uint v) {
    return vec3(uintBitsToFloat(vertex_words[v * 8u + 3u]), uintBitsToFloat(vertex_words[v * 8u + 4u]),
                uintBitsToFloat(vertex_words[v * 8u + 5u]));
}
vec4 vertex_weights(uint v) { return unpackUnorm4x8(vertex_words[v * 8u + 6u]); }

// How much the ground at a point carries grass, 0 … 1: soil (bedrock's weight) below the snow
// line as the terrain shader tints it green, sand thinly, rocks and water beds never.
float grass_grow(vec4 w, float height) {
    w /= max(dot(w, vec4(1.0)), 1e-4);
    float below_snow = 1.0 - smoothstep(u_snow_height - 40.0, u_snow_height - 10.0, height);
    float shore = smoothstep(u_sea_level + 0.5, u_sea_level + 2.0, height);
    return clamp((w.x + 0.35 * w.y) * below_snow * shore, 0.0, 1.0);
}

bool has_sky(vec3 local) {
    ivec2 column = ivec2(floor(local.xz + u_tops_origin));
    if (any(lessThan(column, ivec2(0))) || any(greaterThanEqual(column, ivec2(u_tops_size)))) return true;
    return local.y + u_origin_y >= tops[column.y * u_tops_size + column.x] - SKY_MARGIN;
}

void main() {
    uint t = gl_GlobalInvocationID.x;
    if (t >= u_triangle_count) return;
    uint ia = indices[3u * t], ib = indices[3u * t + 1u], ic = indices[3u * t + 2u];
    vec3 a = vertex_position(ia), b = vertex_position(ib), c = vertex_position(ic);
    uint offset = u_write != 0 ? counts[t] : 0u, count = 0u;
    vec3 face = cross(b - a, c - a);
    // Faces steeper than the slope limit by far, or facing down, have no grass (and little or
    // no area seen from above).
    float face_length = length(face);
    if (face_length > 0.0 && face.y / face_length > 0.5) {
        float k = float(u_density);
        vec2 lo = min(a.xz, min(b.xz, c.xz)), hi = max(a.xz, max(b.xz, c.xz));
        ivec2 first = ivec2(floor(lo * k)), last = ivec2(floor(hi * k));
        // Barycentric coordinates seen from above: p = a + wb·(b − a) + wc·(c − a) in (x, z).
        vec2 ab = b.xz - a.xz, ac = c.xz - a.xz;
        float area = ab.x * ac.y - ab.y * ac.x;
        for (int j = first.y; j <= last.y; j++)
            for (int i = first.x; i <= last.x; i++) {
                uint ci = u_origin_cell.x + uint(i), cj = u_origin_cell.y + uint(j);
                uint h = grass_hash3(ci, cj, u_seed);
                vec2 p = (vec2(i, j) + vec2(grass_unit(h), grass_unit(grass_hash(h)))) / k;
                vec2 ap = p - a.xz;
                float wb = (ap.x * ac.y - ap.y * ac.x) / area;
                float wc = (ab.x * ap.y - ab.y * ap.x) / area;
                float wa = 1.0 - wb - wc;
                if (wa < 0.0 || wb < 0.0 || wc < 0.0) continue;
                vec3 position = wa * a + wb * b + wc * c;
                vec3 n = normalize(wa * vertex_normal(ia) + wb * vertex_normal(ib) + wc * vertex_normal(ic));
                float slope = (1.0 - clamp(n.y, 0.0, 1.0)) * 90.0;              // 002 §3.3
                if (slope >= u_slope_limit) continue;
                float height = position.y + u_origin_y;
                if (height <= u_sea_level) continue;
                vec4 w = wa * vertex_weights(ia) + wb * vertex_weights(ib) + wc * vertex_weights(ic);
                float grow = grass_grow(w, height);
                uint seed = grass_hash(h ^ 0x9e3779b9u);
                if (grass_unit(grass_hash(seed)) >= grow || !has_sky(position)) continue;
                if (u_write != 0) {
                    tufts[2u * (offset + count)] = vec4(position, uintBitsToFloat(seed));
                    tufts[2u * (offset + count) + 1u] = vec4(n, grow);
                }
                count++;
            }
    }
    if (u_write == 0) counts[t] = count;
}
