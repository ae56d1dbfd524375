/* terrain_world_edit.c — a tool applied to the world (terrain.h, "edits in the world").
 *
 * Tools work on a terrain_columns region; the world holds immutable stacks. An edit therefore
 * loads the chunks the tool can reach into one region (whole chunks, so that each changed chunk
 * comes back complete), applies the tool there and commits every chunk with a changed column.
 * The reach includes the field's margin: sculpting and sweeping read f one kernel (σ = one
 * column) beyond the columns they rewrite, and the tools want two columns of slack
 * (terrain_sculpt's rule).
 */
#include "terrain/edit/terrain_edit_internal.h"

#include "core/core.h"

#include <math.h>

#define EDIT_MARGIN_COLUMNS 2.0
#define EDIT_MAX_CHUNKS_PER_SIDE 8          /* a region of at most 8 × 8 chunks (256 m) */

/* The world-metre rectangle [x0, x1] × [z0, z1] the edit can change or read; false for an edit
 * whose extent is not a finite rectangle. */
static bool edit_extent(const terrain_edit *edit, double *x0, double *x1, double *z0, double *z1) {
    double reach;
    switch (edit->tool) {
    case TERRAIN_EDIT_SCULPT_ADD:
    case TERRAIN_EDIT_SCULPT_CARVE:
        /* The ball's centre lies within R of the target (δ ≤ R), its reach R beyond. */
        reach = 2.0 * (double)edit->sculpt.radius + EDIT_MARGIN_COLUMNS;
        *x0 = edit->sculpt.target[0] - reach, *x1 = edit->sculpt.target[0] + reach;
        *z0 = edit->sculpt.target[2] - reach, *z1 = edit->sculpt.target[2] + reach;
        break;
    case TERRAIN_EDIT_SWEEP: {
        const terrain_sweep_desc *d = &edit->sweep;
        if (!d->points || d->point_count <= 0) return false;
        float largest = d->radius;
        for (int i = 0; d->radii && i < d->point_count; i++) largest = fmaxf(largest, d->radii[i]);
        reach = (double)largest * terrain__sweep_reach_scale(d) + EDIT_MARGIN_COLUMNS;
        *x0 = *z0 = INFINITY, *x1 = *z1 = -INFINITY;
        for (int i = 0; i < d->point_count; i++) {
            *x0 = fmin(*x0, d->points[i][0] - reach), *x1 = fmax(*x1, d->points[i][0] + reach);
            *z0 = fmin(*z0, d->points[i][2] - reach), *z1 = fmax(*z1, d->points[i][2] + reach);
        }
        break;
    }
    case TERRAIN_EDIT_DEPOSIT:
        reach = (double)edit->deposit.radius + 1.0;
        *x0 = edit->deposit.x - reach, *x1 = edit->deposit.x + reach;
        *z0 = edit->deposit.z - reach, *z1 = edit->deposit.z + reach;
        break;
    case TERRAIN_EDIT_ERODE:
        reach = (double)edit->erode.radius + 1.0;
        *x0 = edit->erode.x - reach, *x1 = edit->erode.x + reach;
        *z0 = edit->erode.z - reach, *z1 = edit->erode.z + reach;
        break;
    default:
        return false;
    }
    return isfinite(*x0) && isfinite(*x1) && isfinite(*z0) && isfinite(*z1) && *x0 <= *x1 && *z0 <= *z1;
}

static bool edit_apply(terrain_columns *region, const terrain_edit *edit) {
    switch (edit->tool) {
    case TERRAIN_EDIT_SCULPT_ADD:
    case TERRAIN_EDIT_SCULPT_CARVE: {
        terrain_sculpt_desc sculpt = edit->sculpt;
        sculpt.carve = edit->tool == TERRAIN_EDIT_SCULPT_CARVE;
        return terrain_sculpt(region, &sculpt, NULL);
    }
    case TERRAIN_EDIT_SWEEP: return terrain_sweep(region, &edit->sweep, NULL);
    case TERRAIN_EDIT_DEPOSIT: return terrain_deposit(region, &edit->deposit, NULL);
    case TERRAIN_EDIT_ERODE: return terrain_erode(region, &edit->erode, NULL);
    default: return false;
    }
}

int terrain_world_edit(terrain_world *world, const terrain_edit *edit, terrain_chunk_coord *changed, int capacity) {
    double x0, x1, z0, z1;
    if (!edit) {
        core_log_error("terrain", "edit: no edit given");
        return -1;
    }
    if (!edit_extent(edit, &x0, &x1, &z0, &z1)) {
        core_log_error("terrain", "edit: %s (tool %d): not a brush, or its position is not finite: ignored",
                   terrain_edit_tool_name(edit->tool), (int)edit->tool);
        return -1;
    }
    double chunk = TERRAIN_CHUNK_COLUMNS * TERRAIN_COLUMN_SIZE;
    double cx0 = floor(x0 / chunk), cx1 = floor(x1 / chunk), cz0 = floor(z0 / chunk), cz1 = floor(z1 / chunk);
    if (cx1 - cx0 >= EDIT_MAX_CHUNKS_PER_SIDE || cz1 - cz0 >= EDIT_MAX_CHUNKS_PER_SIDE ||
        fabs(cx0) > 1e15 || fabs(cz0) > 1e15) {
        core_log_error("terrain", "edit: %s reaches %.0f × %.0f chunks (at most %d × %d): ignored",
                   terrain_edit_tool_name(edit->tool), cx1 - cx0 + 1, cz1 - cz0 + 1, EDIT_MAX_CHUNKS_PER_SIDE,
                   EDIT_MAX_CHUNKS_PER_SIDE);
        return -1;
    }
    int64_t first_x = (int64_t)cx0, first_z = (int64_t)cz0;
    int chunks_x = (int)(cx1 - cx0) + 1, chunks_z = (int)(cz1 - cz0) + 1;
    terrain_columns *region = terrain_columns_create(&(terrain_columns_desc){
        .x = first_x * TERRAIN_CHUNK_COLUMNS, .z = first_z * TERRAIN_CHUNK_COLUMNS,
        .width = chunks_x * TERRAIN_CHUNK_COLUMNS, .depth = chunks_z * TERRAIN_CHUNK_COLUMNS });
    if (!region) return -1;
    for (int k = 0; k < chunks_z; k++)
        for (int i = 0; i < chunks_x; i++) {
            terrain_chunk_coord coord = { first_x + i, first_z + k };
            terrain_columns_load(region, coord, terrain_world_stacks(world, coord));
        }
    terrain_columns_changed_chunks(region, NULL, 0, true);    /* loading is not an edit */
    int count = -1;
    if (edit_apply(region, edit)) {
        int32_t sea;
        if (terrain__world_sea(world, &sea)) terrain__columns_flood(region, sea);   /* the sea comes in */
        terrain_chunk_coord touched[EDIT_MAX_CHUNKS_PER_SIDE * EDIT_MAX_CHUNKS_PER_SIDE];
        count = terrain_columns_changed_chunks(region, touched, (int)(sizeof touched / sizeof *touched), true);
        for (int c = 0; c < count; c++) {
            terrain_stacks *stacks = terrain_columns_to_stacks(region, touched[c]);
            if (stacks) terrain_world_commit(world, touched[c], stacks, edit->tool);
            if (c < capacity && changed) changed[c] = touched[c];
        }
    }
    terrain_columns_destroy(region);
    return count;
}
