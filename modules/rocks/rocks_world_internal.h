/* rocks_world_internal.h — private to modules/rocks: what the placement, the ECS system and the
 * renderer share: the renderer's calls. (rocks_internal.h holds the tile set's internals.) */
#ifndef ROCKS_WORLD_INTERNAL_H
#define ROCKS_WORLD_INTERNAL_H

#include "rocks/rocks.h"

typedef struct rocks_renderer rocks_renderer;

/* The tile set's rock levels kept compact on the CPU (the set's meshes may be released after),
 * and the frame's batch of placed vertices with its GPU buffers. */
rocks_renderer *rocks__renderer_create(gfx_context *gfx, const rocks_tileset *set);
void rocks__renderer_destroy(rocks_renderer *r);
size_t rocks__renderer_gpu_bytes(const rocks_renderer *r);   /* its buffers' sizes */
size_t rocks__renderer_cpu_bytes(const rocks_renderer *r);   /* the kept levels and the staging */
typedef struct rocks_draw_desc {
    float tile_size, range, fog_density;
    float lod_distance[ROCKS_LODS - 1];
} rocks_draw_desc;
/* Draws the placements' rocks in view (one pass "rocks", one draw call); returns the rocks drawn
 * and their triangles in *triangles. */
uint64_t rocks__renderer_draw(rocks_renderer *r, const terrain_view *view, const rocks_draw_desc *params,
                              const rocks_placement *const *placements, int count, uint64_t *triangles);

/* Block copy `block` of the tile copy at tile coordinate `cell` raised into the field's samples
 * inside its bounds (rocks_blocks.c; the cliffs' amplifier shares it); false when its bounds
 * hold none of them. */
bool rocks__amplify_copy(const rocks_block_tile *tile, uint32_t block, const double cell[3], terrain_field *field);

/* Coarse fields (003 §5 at a level of detail; rocks_blocks.h, rocks_block_tile_amplify, says
 * why): in a field sampled every `spacing` = h > 1 m a block of smallest width w
 * (rocks_block_tile.widths) shows only when w > ROCKS__COARSE_MIN_WIDTH · h, lowered by
 * h − w/2 when w < 2h (0 when w ≥ 2h); rocks__coarse_erosion gives INFINITY for one not shown.
 * 1.5: what the box filter leaves of a block, 2(w − h), is then at least h thick, so every row
 * of samples across it meets it (thinner, it would bead into bumps that move with the grid).
 * Fields at 1 m show every block as it is (min width −INFINITY, erosion 0). */
#define ROCKS__COARSE_MIN_WIDTH 1.5f
float rocks__coarse_min_width(float spacing);
float rocks__coarse_erosion(float width, float spacing);
/* A block's smallest width, metres: the least extent along its planes' normals (rocks_blocks.c
 * says where that errs); a block placed by hand, its box's smallest side. */
float rocks__block_width(const rocks_block_tile *tile, uint32_t block);

/* The tile copies (their tile coordinates c0 … c1, inclusive) some block of which can reach the
 * box [lo, hi]: the union of the blocks' bounds, moved by whole tiles, meets it. */
void rocks__cell_range(const rocks_block_tile *tile, const double lo[3], const double hi[3], int64_t c0[3],
                       int64_t c1[3]);
/* rocks_block_on_walls, with the field's gradient at the anchor in g (unnormalised; written
 * whenever the anchor is near the surface): the cliffs read the wall's inside from it. */
bool rocks__wall_at(const rocks_wall_presence *walls, const double anchor[3], float g[3]);
/* A block type's default fracture spacing and main disc radius (rocks_blocks.c), metres; the
 * cliffs scale both by their block_scale. */
void rocks__block_type_defaults(rocks_block_type type, float *spacing, float *radius);

#endif
