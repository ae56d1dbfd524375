/* terrain_edit.h — editing the terrain (modules/terrain/edit/): a mutable region of columns
 * (terrain_columns), stabilization by the angle of repose (000 §3.4), the deposit and erosion
 * brushes (000 §4.3, §4.4), sculpting and sweeping (000 §4.1, §4.2), picking, and a tool applied
 * to a world's chunks (terrain_world_edit). Built on data/terrain_data.h; terrain/terrain.h
 * includes it.
 *
 *     terrain_ray_hit hit;
 *     if (terrain_raycast(world, eye, forward, 64, &hit)) {
 *         terrain_chunk_coord changed[16];
 *         terrain_world_edit(world, &(terrain_edit){ .tool = TERRAIN_EDIT_SCULPT_CARVE,
 *             .sculpt = { .target = { hit.position[0], hit.position[1], hit.position[2] },
 *                         .radius = 3 } }, changed, 16);
 *     }
 *
 * Threads: a region is plain data, one call at a time on it; terrain_world_edit runs on the main
 * thread between frames' jobs. A running world edits through terrain_ecs_edit (ecs/terrain_ecs.h),
 * which also stabilizes what changed.
 */
#ifndef TERRAIN_EDIT_H
#define TERRAIN_EDIT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "terrain/data/terrain_data.h"

/* ---- editing: columns, stabilization, brushes (000 §3.4, §4) ---- */

/* Editing works on a mutable copy of some columns, a terrain_columns region: any W × D columns
 * (one chunk, or several), thicknesses in integer quanta so that every edit conserves the mass
 * of each material exactly. Brushes drop sand or rocks (000 §4.3) or turn bedrock into them
 * (§4.4); stabilization then moves sand and rocks down slopes steeper than their angle of
 * repose (§3.4), a little per iteration, until nothing moves or the call's budget is spent.
 *
 *     terrain_columns *region = terrain_columns_create(&(terrain_columns_desc){
 *         .x = 0, .z = 0, .width = 64, .depth = 64 });           // chunks (0,0) … (1,1)
 *     for (int n = 0; n < 4; n++) terrain_columns_load(region, chunks[n], stacks[n]);
 *     terrain_deposit(region, &(terrain_deposit_desc){ .x = 32, .z = 32, .radius = 8,
 *                                                      .volume = 500 }, NULL);    // sand
 *     terrain_stabilize_result result;
 *     terrain_stabilize_region(region, &(terrain_stabilize_desc){ .budget_ns = 2000000 },
 *                              jobs, &result);                   // again next frame until
 *                                                                // result.converged
 *     terrain_chunk_coord changed[4];
 *     int n = terrain_columns_changed_chunks(region, changed, 4, true);
 *     for (int c = 0; c < n; c++) replace(changed[c], terrain_columns_to_stacks(region, changed[c]));
 *     terrain_columns_destroy(region);
 *
 * Layer order (000 §3.4): between two stable layers (bedrock, or a custom material) granular
 * material is merged and sorted sand, rocks, water, air — what lies over a cave falls to its
 * floor, and a cave roof holds what lies on it. Both the pile above a column's highest stable
 * layer and the piles on cave floors flow (000 §3.4 stabilizes "all material layers located
 * between two stable bedrock layers"). Stabilization moves each material on its own surface,
 * bottom layer first (sand on the sand surface, rocks on the ground), so a stable column has no
 * neighbour lower than d·tan(angle) + tolerance below either surface, d the distance between
 * column centres (1 m, or √2 m diagonally). A cave pile's neighbour is the space of the next
 * column at the height the material slides at (the same cave, or the open ground outside its
 * mouth); rock at that height is a wall, and a space under a roof takes no more than its air, so
 * a pile spreads on the cave's floor and never grows into the roof.
 *
 * Determinism: an iteration is nine passes, one per colour of a 3 × 3 pattern of columns (by
 * world column index); columns of one colour are three apart, so their moves never touch the
 * same column and a pass can move them all at once, in integer quanta. The result does not
 * depend on the thread count, on how a pass is split into jobs, or on how the columns are split
 * into regions (terrain_stabilize_regions), and a call that stops on its budget continues exactly
 * where it stopped. A pile on a cave floor crosses regions' borders alike; where no region
 * continues it stops as at a wall and wakes nothing (TERRAIN_EDGE_WAKE reports top piles only). Only columns next to a change are looked at: edits (brushes,
 * terrain_columns_set, terrain_columns_touch) are changes, and so is every moved quantum.
 *
 * Threads: a region is plain data; one call at a time on it. Errors (a bad size, NaN, an unknown
 * material) return false or NULL with a message logged, never a crash. */

typedef struct job_system job_system;

typedef struct terrain_columns terrain_columns;

typedef struct terrain_columns_desc {
    int64_t x, z;                     /* world column index of the first column (chunk c's first
                                         column is c·TERRAIN_CHUNK_COLUMNS) */
    int width, depth;                 /* columns along x and z: 1 … 4096, at most 2^22 in all */
} terrain_columns_desc;

/* Every column empty (only the implicit bedrock below the floor). NULL (message logged) for a
 * bad size. Free with terrain_columns_destroy. */
terrain_columns *terrain_columns_create(const terrain_columns_desc *desc);
void terrain_columns_destroy(terrain_columns *columns);
terrain_columns_desc terrain_columns_extent(const terrain_columns *columns);

/* Copies the chunk's columns that lie in the region over the region's (not marked for
 * stabilization; columns out of order are sorted by the next stabilization). False (message
 * logged) when the chunk does not overlap the region or a column is absurdly tall. */
bool terrain_columns_load(terrain_columns *columns, terrain_chunk_coord coord, const terrain_stacks *stacks);
/* The chunk's columns as stacks (an unedited chunk comes back byte for byte); the chunk must lie
 * inside the region, else NULL (message logged). Free with terrain_stacks_destroy. */
terrain_stacks *terrain_columns_to_stacks(const terrain_columns *columns, terrain_chunk_coord coord);

/* Column (i, k) of the region (0 ≤ i < width, 0 ≤ k < depth), bottom-up from TERRAIN_FLOOR_Y,
 * adjacent equal materials merged; returns the count (writes at most `capacity`), −1 for a
 * column outside the region. */
int terrain_columns_get(const terrain_columns *columns, int i, int k, terrain_layer *layers, int capacity);
/* Replaces column (i, k) by `layers` (bottom-up; thicknesses rounded to the quantum by their
 * cumulative heights, as the stacks builder does) and marks it changed. False (message logged,
 * column unchanged) for a column outside the region, an unknown material, or a thickness that is
 * negative, NaN or too large. */
bool terrain_columns_set(terrain_columns *columns, int i, int k, const terrain_layer *layers, int count);
/* Top of the highest layer that is not air or water (as terrain_stacks_top). */
float terrain_columns_top(const terrain_columns *columns, int i, int k);
/* Volume of `material` in the region, in quanta·column (1/32 m³). */
int64_t terrain_columns_mass(const terrain_columns *columns, terrain_material material);
/* Marks columns [i0, i1) × [k0, k1) (clipped to the region) changed, so that the next
 * stabilization looks at them — e.g. every column of a freshly generated chunk. */
void terrain_columns_touch(terrain_columns *columns, int i0, int k0, int i1, int k1);
/* The chunks with a column whose content changed (edits, sorting, stabilization) since the last
 * clear, in z-major order; returns how many there are (writes at most `capacity`). With `clear`
 * the record starts afresh. A remesh must also take the neighbours the field's kernel reaches. */
int terrain_columns_changed_chunks(terrain_columns *columns, terrain_chunk_coord *out, int capacity, bool clear);

/* ---- stabilization (000 §3.4) ---- */

typedef enum terrain_stabilize_edge {
    TERRAIN_EDGE_WALL,                /* beyond the regions nothing exists: nothing flows there */
    TERRAIN_EDGE_WAKE,                /* stop before a pass that needs columns beyond the regions
                                         and name their regions in result.woken; add them and call
                                         again (at the world's end, call with WALL instead) */
} terrain_stabilize_edge;

typedef struct terrain_stabilize_desc {
    float sand_angle;                 /* degrees of repose, 0 < angle < 90; 0 = 33 (000: 30–35) */
    float rocks_angle;                /* 0 = 42 (000: 40–45) */
    float step;                       /* metres a column gives away per material and look at most
                                         (000 §3.4's "small constant amount a"; it also never gives
                                         more than levels it with its neighbours); rounded to the
                                         quantum, at least one; 0 = 1 m */
    float tolerance;                  /* metres a slope may exceed d·tan(angle) by; 0 = none */
    int max_iterations;               /* per call (an iteration looks at every column once);
                                         0 = no limit */
    uint64_t budget_ns;               /* per call, checked between passes once an iteration has
                                         run; 0 = no limit. For a world that is a pure function of
                                         its edit log, budget in iterations: where a time budget
                                         stops depends on the machine */
    terrain_stabilize_edge edge;
} terrain_stabilize_desc;

#define TERRAIN_STABILIZE_MAX_WOKEN 32

typedef struct terrain_stabilize_result {
    bool converged;                   /* nothing left to move: the regions are stable */
    int iterations;                   /* run by this call */
    int64_t moved;                    /* quanta·column moved between columns by this call */
    /* Regions missing beyond the edge where material reached it (WALL) or is about to cross it
     * (WAKE: add them and call again), as grid coordinates in units of the region size —
     * chunk coordinates for regions of one chunk. woken_count may exceed the array. */
    int woken_count;
    terrain_chunk_coord woken[TERRAIN_STABILIZE_MAX_WOKEN];
} terrain_stabilize_result;

/* Stabilizes the region (its border is the edge). jobs may be NULL (one thread); the result is
 * the same for any thread count. False (message logged, nothing changed) for bad parameters. */
bool terrain_stabilize_region(terrain_columns *columns, const terrain_stabilize_desc *params, job_system *jobs,
                              terrain_stabilize_result *result);
/* Stabilizes regions side by side as one: material flows across their borders, and the outcome
 * equals that of a single region covering them all (same iterations, same bytes). The regions
 * must have one size and lie on the grid of that size (origins multiples of it apart), e.g. one
 * per chunk; the edge is where no region continues. False (message logged) for bad parameters,
 * unequal sizes, misaligned or repeated regions. */
bool terrain_stabilize_regions(terrain_columns *const *regions, int count, const terrain_stabilize_desc *params,
                               job_system *jobs, terrain_stabilize_result *result);

/* ---- brushes (000 §4.3, §4.4) ---- */

typedef enum terrain_falloff {
    TERRAIN_FALLOFF_DEFAULT = 0,      /* smooth */
    TERRAIN_FALLOFF_SMOOTH,           /* (1 − r²/R²)², 000 §4.1's g(r) */
    TERRAIN_FALLOFF_FLAT,             /* the same everywhere inside R */
} terrain_falloff;

/* What a brush adds, as a desc names it. Zero is the tool's default (CONVENTIONS.md: no zero is
 * also a real value), so these are not terrain_material's values: the stored material (bytes in
 * stacks and edit files) stays as it is; each tool maps these onto it. */
typedef enum terrain_brush_material {
    TERRAIN_BRUSH_DEFAULT = 0,        /* the tool's own: sand for a deposit, bedrock for a sculpt */
    TERRAIN_BRUSH_BEDROCK,
    TERRAIN_BRUSH_SAND,
    TERRAIN_BRUSH_ROCKS,
} terrain_brush_material;

/* Drops `volume` m³ of sand or rocks on the columns whose centres lie within `radius` of (x, z)
 * (world metres), distributed by the falloff and rounded so that the total is exact (to the
 * quantum·column): a brush that overhangs the region's border puts it all on the columns inside.
 * It lands on each column's pile (sorted: sand goes under rocks, both under water).
 *
 * At a height (at_height): in each column it lands in the space nearest y — the run between a
 * stable layer and the next one above (a cave), or the open pile on top — on that space's floor,
 * so that sand dropped in a cave lies on the cave's floor and the rock above is unchanged. The
 * layers below and above that space stay as they were; within it the material goes under the
 * water (which it displaces, as on open ground) and takes the air's place. A space under a roof
 * takes no more than its air and water: a cave filled to its roof takes nothing more, and
 * `quanta` then reports less than the volume (the region gains exactly what it reports). Where
 * the nearest space is the open top, the deposit is the same as without at_height. */
typedef struct terrain_deposit_desc {
    terrain_brush_material material;  /* TERRAIN_BRUSH_SAND or _ROCKS; 0 = sand */
    double x, z;
    float radius;                     /* metres, > 0 */
    double volume;                    /* m³, ≥ 0 */
    terrain_falloff falloff;
    bool at_height;                   /* false (default): each column's top pile; true: the
                                         space of each column nearest y */
    double y;                         /* world metres; read only with at_height */
} terrain_deposit_desc;

typedef enum terrain_erode_mode {
    TERRAIN_ERODE_DEFAULT = 0,        /* surface */
    TERRAIN_ERODE_SURFACE,            /* each column under the disc whose highest stable layer is
                                         bedrock loses depth·falloff from its top (with at_height:
                                         the stable layer under the column's space nearest y, a
                                         cave's floor when y is on it) */
    TERRAIN_ERODE_COLLAPSE,           /* all bedrock inside the ball of radius R around (x, y, z)
                                         turns granular; with what lay on it, it falls to the next
                                         stable layer below (bedrock above stays: it is stable) */
} terrain_erode_mode;

/* Turns bedrock into granular material where the tool reaches (000 §4.4): a share rocks_ratio
 * (ρ) of it into rocks, the rest into sand, exactly (per column, bedrock quanta removed = sand +
 * rocks quanta added). The material stays in its column until stabilization moves it. */
typedef struct terrain_erode_desc {
    terrain_erode_mode mode;
    double x, y, z;                   /* centre, world metres (y: collapse, or surface with
                                         at_height) */
    float radius;                     /* metres, > 0 */
    float depth;                      /* surface: metres eroded at the centre, ≥ 0 */
    float rocks_ratio;                /* ρ ∈ [0, 1]; 0 = all sand */
    terrain_falloff falloff;          /* surface only */
    bool at_height;                   /* surface only: false (default) the highest stable layer;
                                         true the floor of the space nearest y */
} terrain_erode_desc;

/* Both return false (message logged, region unchanged) for bad parameters or a deposit that
 * misses the region; `quanta` (may be NULL) receives the quanta·column deposited or eroded.
 * Changed columns are marked for the next stabilization. */
bool terrain_deposit(terrain_columns *columns, const terrain_deposit_desc *desc, int64_t *quanta);
bool terrain_erode(terrain_columns *columns, const terrain_erode_desc *desc, int64_t *quanta);

/* ---- sculpting and sweeping (000 §4.1, §4.2), picking ---- */

/* Sculpt (000 §4.1): a point primitive f*(p) = g(|p − c|), g(r) = (1 − r²/R²)² inside R, is
 * blended into the field — fe = f + f* to add, fe = f − f* to carve — with its centre δ inside
 * the surface to add (c = v − δn) or outside to carve (c = v + δn), v the target moved onto the
 * surface f = 0 along the field's normal n = −∇f/|∇f| (which points into the air), at most half a
 * metre. The columns under the ball are rebuilt along their central axes: over the ball's chord,
 * the signs of f and fe are sampled and their roots bisected to the height quantum (a quantum is
 * solid where the field at its centre is > 0). Only the quanta the edit flips change, so a column
 * stays exactly as it was wherever the edit does not change the field's sign (the ball's rim,
 * above and below): adding turns the air and water where f ≤ 0 < fe into `material` (solid that
 * is there keeps its kind), carving turns everything where fe ≤ 0 < f into air. A flipped stretch
 * takes along the column's own quanta next to it that the field does not see — air over which
 * added material would float (fe > 0), bedrock that would float over a carved gap (fe ≤ 0) — so
 * no edit leaves a hidden sliver or gap. Granular material left over a carved span stays until
 * stabilization.
 *
 *     terrain_ray_hit hit;
 *     if (terrain_raycast(world, eye, forward, 64, &hit))
 *         terrain_sculpt(region, &(terrain_sculpt_desc){ .target = { hit.position[0], … },
 *                                                        .radius = 3, .carve = true }, NULL);
 *
 * The field is computed from the region's own columns (a snapshot taken before anything is
 * written), so the region must hold every column within R + δ + 2 metres of the target along x
 * and z (the ball's centre may lie δ to the side on a wall; the field reads a column beyond the
 * ball) — a region of whole chunks around it; terrain_world_edit does this. False (message
 * logged, region unchanged) for bad parameters (NaN, R outside (0, 32], an offset outside
 * [0, 1], a material other than bedrock or sand), a region without that margin, or a target
 * with no surface within half a metre (the field is flat there). `changed` (may be NULL)
 * receives how many columns changed; only those are marked for stabilization and reported by
 * terrain_columns_changed_chunks. */
typedef struct terrain_sculpt_desc {
    double target[3];                 /* v: a point on the surface or within ½ m of it (world
                                         metres; y within the floor − 64 … floor + 2^20) */
    float radius;                     /* R, metres, 0 < R ≤ 32 */
    float offset;                     /* δ / R, 0 … 1; 0 = 0.5 (000: δ = R/2 works well) */
    bool carve;                       /* false: add material; true: carve it away */
    terrain_brush_material material;  /* what added material is: TERRAIN_BRUSH_BEDROCK or _SAND
                                         (in the field); 0 = bedrock */
} terrain_sculpt_desc;

bool terrain_sculpt(terrain_columns *columns, const terrain_sculpt_desc *desc, int64_t *changed);

/* Sweep (000 §4.2): carves the union of swept balls around a graph of segments — a tunnel, a
 * crack, a ravine, a cave network — as fe = min(f, −f*): everything within the profile radius
 * of the skeleton becomes air, exactly (no surface projection: the graph is where it is). The
 * radius is interpolated linearly along each segment from its end points' radii (a segment's
 * volume is the convex hull of its two end balls). Columns are rebuilt along their axes by the
 * roots of fe as for sculpting: a quantum whose centre lies inside the volume becomes air,
 * whatever it held; outside the volume the layers stay as they were. Granular material above a
 * carved span stays where it is until stabilization lets it fall. Same region rule as
 * terrain_sculpt: every column within the largest radius + 2 metres of the skeleton (its
 * bounding box grown by that). False (message logged, region unchanged) for bad parameters:
 * no points, a count out of range, a NaN point, a radius outside (0, 32], a segment naming a
 * point that does not exist. `changed` (may be NULL) receives how many columns changed. */
typedef struct terrain_sweep_desc {
    const double (*points)[3];        /* skeleton vertices, world metres */
    const float *radii;               /* per vertex, metres, 0 < r ≤ 32; NULL = `radius` for all */
    int point_count;                  /* 1 … 4096 (1: a ball) */
    const int (*segments)[2];         /* pairs of vertex indices (equal: a ball); NULL = the
                                         polyline 0-1-2-… */
    int segment_count;                /* with segments: 1 … 16384; ignored without */
    float radius;                     /* when radii is NULL */
    /* Profile curve (000 §4.2: "piecewise cubic spline curves [that] may define non convex ...
     * cross sections"): the cross-section swept along each segment, as a radius scale ρ(θ) around
     * the skeleton, a periodic Catmull-Rom cubic through profile[j] at θ_j = 2πj/profile_count,
     * θ = 0 along the surface's normal (−∇f, into the air) taken perpendicular to the segment and
     * θ = 90° along tangent × normal; where the field is flat (deep in rock) θ = 0 is up. A point
     * p is carved when, with t its position along the segment (0 … 1, the ends cut flat: a
     * prism, no round caps) and w its offset from the axis, |w| < r(t)·ρ(θ). NULL (the default):
     * no profile, the round sweep above, exactly as before. A segment of no length stays a ball. */
    const float *profile;             /* profile_count scales, each 0 … 4 */
    int profile_count;                /* with profile: 3 … 64 */
    /* 000 §4.2 step 1: project the graph onto the surface — every point is first moved down (or
     * up) its column onto the ground, the top of the column's highest solid (cracks and ravines
     * drawn over the terrain); false (the default): the graph is where it is (tunnels, caves). */
    bool project;
} terrain_sweep_desc;

bool terrain_sweep(terrain_columns *columns, const terrain_sweep_desc *desc, int64_t *changed);

/* Picking: the first point along the ray where the field f crosses from air to solid (what the
 * mesh shows; water is not in the field, so a ray goes through it to the ground), within
 * max_distance metres; marches terrain_field_at in steps of at most half a metre and bisects the
 * crossing. A feature the field shows over less than half a metre of the ray may be missed. An
 * origin already inside (f > 0) is a hit at distance 0 there. The direction need not be unit
 * length. Generates the chunks it reads. Thread-safe as terrain_world_stacks. False (message
 * logged) for a NaN or zero direction, a NaN origin or max_distance outside (0, 100000]; false
 * without a message for a miss. `hit` may be NULL. */
typedef struct terrain_ray_hit {
    double position[3];
    float normal[3];                  /* unit, into the air (−∇f / |∇f|, central differences ½ m
                                         apart); −direction where the field is flat (deep inside) */
    float distance;                   /* metres from the origin along the unit direction */
    terrain_material material;        /* of the column layer just inside the surface: the first
                                         sand or bedrock within 1 m along −normal, else what is at
                                         the hit */
} terrain_ray_hit;

bool terrain_raycast(terrain_world *world, const double origin[3], const float direction[3], float max_distance,
                     terrain_ray_hit *hit);

/* ---- edits in the world ----
 *
 * With terrain_world_desc.edits set, the world replays a chunk's log whenever it generates the
 * chunk, and terrain_world_commit (data/terrain_data.h, "commits") records what changes. A tool
 * applied to the world:
 *
 *     terrain_chunk_coord changed[16];
 *     int n = terrain_world_edit(world, &(terrain_edit){ .tool = TERRAIN_EDIT_SCULPT_CARVE,
 *                                 .sculpt = { .target = { x, y, z }, .radius = 3 } },
 *                                changed, 16);
 *
 * loads a region of the chunks the tool reaches (with the field's margin), applies the tool
 * there and commits each changed chunk. Stabilization is separate (terrain_ecs does it on the
 * chunks that changed, a few iterations a frame). */
typedef struct terrain_edit {
    terrain_edit_tool tool;           /* SCULPT_ADD/CARVE, SWEEP, DEPOSIT or ERODE */
    terrain_sculpt_desc sculpt;       /* for SCULPT_* (carve is set from the tool) */
    terrain_sweep_desc sweep;
    terrain_deposit_desc deposit;
    terrain_erode_desc erode;
} terrain_edit;

/* The sea after edits (000 §4: "carving below sea level next to the sea lets the sea in: no dry
 * hole below the water line"). Generation fills the air above each column's highest solid layer
 * up to sea_level with water; edits keep that rule, as a water table at sea level: every column
 * an edit or stabilization changed whose highest solid (sand, rocks, bedrock) lies below
 * sea_level gets water from there exactly up to sea_level — air in that span becomes water, and
 * water of that run above sea_level goes (added material displaced it: it flows off into the
 * sea). Columns whose highest solid is at or above sea_level keep their water as it is (lakes).
 * Added material displaces water everywhere (lakes too): a deposit lowers the water standing on
 * the pile by as much as the pile rises, and a stabilization commit caps the water on a changed
 * column at the surface the column had before (sand that slid under water pushes it out).
 * The rule is applied where the change is committed (terrain_world_edit, and the stabilize
 * phase's commits), column by column from the column alone, so it keeps every determinism
 * invariant (same bytes whatever the thread count or region split; the edit log records the
 * flooded columns, so a replay gives the same bytes). Water is not conserved — it comes from and
 * goes to the sea — while sand and rocks still are, exactly. Worlds with `generate` set have the
 * sea only with terrain_world_desc.sea. */

/* Applies the edit; returns how many chunks changed (their coordinates in `changed`, at most
 * `capacity` written), or −1 (message logged, nothing changed) for a bad edit. Main thread,
 * between frames' jobs (it replaces cached stacks; see terrain_world_commit). */
int terrain_world_edit(terrain_world *world, const terrain_edit *edit, terrain_chunk_coord *changed, int capacity);

#endif
