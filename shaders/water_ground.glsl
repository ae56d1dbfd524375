// water_ground.glsl — the ground's height under a point, from the far terrain's clipmap heights
// (terrain__clipmap_bind_ground): water's depth without reading the frame back. The finest
// level whose grid holds the point answers, interpolated bilinearly between its four texels
// (the drawn triangles differ from that by less than a level's relief over a cell). Heights are
// the clipmap's own (the generator's ground, or what terrain_clipmap.c keeps), not sunk.

const int GROUND_MAX_LEVELS = 12;           // TERRAIN_CLIPMAP_MAX_LEVELS
uniform sampler2DArray u_ground_heights;    // RGBA32F: height in r (see clipmap.vert)
uniform int u_ground_levels;                // 0: no far terrain, nothing known
uniform int u_ground_size;                  // texels along each side of a layer (toroidal)
uniform int u_ground_cells;                 // cells along each side of a level
uniform vec2 u_ground_origin[GROUND_MAX_LEVELS];    // each level's vertex (0, 0) − camera, x and z
uniform float u_ground_spacing[GROUND_MAX_LEVELS];  // metres between its vertices
uniform ivec2 u_ground_start[GROUND_MAX_LEVELS];    // its texel of vertex (0, 0)

float ground_texel(int level, ivec2 texel) {
    return texelFetch(u_ground_heights, ivec3(texel % u_ground_size, level), 0).r;
}

// The world height of the ground under camera-relative (x, z) = p; false where no level reaches.
bool ground_height(vec2 p, out float height) {
    for (int l = 0; l < u_ground_levels; l++) {
        vec2 grid = (p - u_ground_origin[l]) / u_ground_spacing[l];
        if (any(lessThan(grid, vec2(0.0))) || any(greaterThanEqual(grid, vec2(float(u_ground_cells))))) continue;
        ivec2 cell = ivec2(floor(grid));
        vec2 f = grid - vec2(cell);
        ivec2 texel = u_ground_start[l] + cell;     // both ≥ 0: the modulo stays in range
        float h00 = ground_texel(l, texel), h10 = ground_texel(l, texel + ivec2(1, 0));
        float h01 = ground_texel(l, texel + ivec2(0, 1)), h11 = ground_texel(l, texel + ivec2(1, 1));
        height = mix(mix(h00, h10, f.x), mix(h01, h11, f.x), f.y);
        return true;
    }
    height = 0.0;
    return false;
}
