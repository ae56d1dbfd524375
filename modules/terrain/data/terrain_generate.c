/* terrain_generate.c — a chunk's stacks from 3D noise (002 §3.1.3, 004 §2).
 *
 * The density of a point is
 *     d(x, y, z) = min(d_ground, d_cave), solid where d > 0
 *     d_ground   = G(x + A·u(x, y, z), z + A·w(x, y, z)) − y                       (002 §3.1.3.1)
 *     G(x, z)    = cliffs(base + relief·shape(M(x, z))) + V·fbm2(x, z)        (M: 004 §2)
 *     d_cave     = (1 − t·a(y) − R₁(Φ(p))·R₂(Φ(p)))·scale        (002 §3.1.3.2, Fig. 11)
 *
 *  - The ground/sky split is the height gradient G − y (002 Fig. 3). Its y perturbation V·fbm2
 *    is a 2D fBm: the paper samples the perturbing fractal "along 0 in the y axis" so that it
 *    acts like a height map and leaves no floating islands (002 Fig. 6, 7). It is added to the
 *    macro relief M, a rescale-and-add multifractal with domain warping (004 §2.1, §2.2; octave
 *    count from the relief's wavelength against the column spacing, no octave shorter than four
 *    columns, fractional last octave, 004 §4.1: relief_octaves), shaped so that peaks rise
 *    faster than seas sink.
 *  - Cliffs (ours, not the papers'): where a low-frequency mask says so, and above the sea, the
 *    macro height is pulled towards terraces of relief/10 metres with steep risers. The papers'
 *    relief alone is rarely steep enough for the overhang shear below to tip it over.
 *  - Overhangs: the sample point is moved sideways by A·(u, w), two 3D fBms (002 Fig. 8, the
 *    "X perturbation", here in x and z). The solid set is then the height field's solid set
 *    pulled back through Φ(x, y, z) = (x + A·u, y, z + A·w); where Φ's horizontal Jacobian is
 *    invertible (A·|∂u/∂x|, … < ½ everywhere) Φ is a homeomorphism and the terrain keeps a height
 *    field's topology — overhangs but no floating islands — whatever the y-derivatives. We
 *    squeeze u and w by 3 along y: steeper shear, more overhangs. An overhang needs
 *    |∇G|·A·|∂u/∂y| > 1, which is why they sit on the cliffs' risers. Nothing bounds A/λ, though,
 *    and caves and the 1 m sampling cut slivers off anyway: islands are removed (below).
 *  - Caves: R₁, R₂ are ridged multifractals (1 on their ridges, where their noise crosses zero);
 *    one alone cuts sheets through the ground, so, as the paper does, two with different seeds
 *    are combined: both near 1 only along the curves where two sheets meet, i.e. tunnels. The
 *    paper multiplies the two clamped maps; we threshold the product, R₁R₂ > 1 − t (our
 *    reading of "only where the values of both fractals are 0 caves will be formed": 0 in the
 *    paper's inverted, clamped map is a ridge here). The second octave has gain 1/4 so that it
 *    roughens the tunnel walls without breaking tunnels into pockets (at gain 1/2 the ridge
 *    value along a tunnel drops to 2/3 wherever octave 2 is far from 0). a(y) is the height
 *    attenuation: 0 above the macro ground G (+ 0.3·fade, so a few tunnels open at the surface;
 *    never under the sea), full from cave_fade_height below that, fading out again at the
 *    bottom of the cave band (fade + 1.5 cave wavelengths deep). Nothing above G is ever cut,
 *    so overhang lips stay whole and caves make no floating islands there.
 *  - The cave map is read where the same displacement moves the point (002 Fig. 11, "distort
 *    the map ... with the perturbing techniques covered in the previous section"): d_cave reads
 *    R₁R₂ at Φ(p), so the caves are pulled back through the same Φ as the ground and bend with
 *    it (cave_lattice).
 *  - Islands (002 §3.1.3: "floating islands which we do not want"): after its columns are made,
 *    a chunk joins its solid runs that share a face (face-adjacent columns whose runs overlap by
 *    two quanta or more as the stacks round them) and turns into air every run that no chain
 *    joins to the floor or to the chunk's outermost columns (islands_remove). What it removes
 *    touches no other chunk's column, so neighbours agree; an island that crosses a chunk border
 *    is beyond one chunk's sight and stays. Measured: none left in 405 chunks of the defaults
 *    (10 floating runs, 3.4 m³, without the removal); with a 30 m shear over 24 m and wide
 *    caves, 6 runs (1.7 m³) across borders in 2 × 2 chunks, from 59 (31 m³). Cost, with the
 *    perturbed caves: +5 % instructions a chunk (callgrind, terrain.generate.128, one thread).
 *
 * Evaluation, per chunk:
 *  1. G on a grid of the chunk's columns plus a margin of ⌈A⌉ + 2, a row at a time with the
 *     vectorised multifractal; it also gives the slopes for sand.
 *  2. Per column, the range of y where the ground can cross: [min G, max G] over the grid
 *     points a displaced sample can read. Below it d_ground > 0, above it d_ground < 0, surely.
 *  3. The 3D noises (u, w and the caves' raw octaves) on a coarse lattice, 4 m apart in x and z
 *     and 2 m in y, u and w with the column batch (terrain__noise3_column), the caves' at each
 *     node's displaced point (terrain__noise3_points); per column they are
 *     interpolated bilinearly to its centre, then linearly along y. Every noise's wavelength is
 *     at least 4 lattice spacings along each axis (u, w: 24 m across, 8 m up; caves 32 m, 21 m),
 *     and the ridge (|n|, a kink) is applied after interpolation, at full resolution.
 *  4. Each column samples d every SAMPLE_STEP (1 m) over its range and places each sign change
 *     by linear interpolation of the full density at the two samples around it; runs of solid
 *     become bedrock, air between solid runs air layers (caves, overhangs). Below the ground's
 *     range only caves can make air, and a 2 m segment of the lattice can only hold a cave if a
 *     bound on R₁R₂ there (the smallest |n| of each octave on the segment) passes the
 *     threshold: most samples cost a comparison.
 *  5. Sand replaces the top of the highest solid run where the macro ground's slope is below
 *     sand_max_slope (thinning to nothing at that slope), rocks lie on it (below, "Rocks"), and
 *     water fills the air above the highest solid run up to sea_level, or up to a lake's level
 *     inside its water circle.
 *
 * Rocks (ours; the issue: "talus at the foot of cliffs, scree on slopes steeper than sand's
 * repose angle, stony river and lake beds"; there are no rivers). A layer of TERRAIN_ROCKS on
 * the top run's sand or bedrock, under any water: the pile order sand, rocks, water, air of
 * 000 §3.4. Where it goes depends on the real tops (the highest crossing of each column, after
 * the shear), not on G: the shear moves cliffs by up to A sideways. Every column of the chunk
 * is generated first; a ring of ROCK_RING columns around it gets an estimated top (ring_top:
 * the ground part only, no caves, from extra lattice nodes around the ring's G), so that piles
 * near a border see the walls and slopes just beyond it and continue across. Over the chunk
 * and ring, from the tops:
 *   - talus: a foot is a column with a neighbour rising faster than FOOT_RISE (1.5 m a metre:
 *     a wall) and none falling faster than ROCK_HOLD_SLOPE (so not a riser's own column). Each
 *     foot holds a cone of rocks talus_depth·smoothstep(rise) high (80–100 % by a noise), its
 *     surface falling at TALUS_SLOPE (35°) out to TALUS_REACH columns; a column's talus is the
 *     highest cone over it less its top: a wedge leaning on the wall, thickest at its foot.
 *   - scree: scree_depth where the ground falls faster than scree_min_slope (sand's 30°) and
 *     slower than 1 m a metre, faded in over 0.08 of slope and cut into patches by a noise of
 *     SCREE_WAVELENGTH.
 *   - lake stones: lake_rocks_depth in a band of the ground from 2 m under to 1.6 m over a
 *     lake's level (its waterline), in patches of a finer noise; the rest of the basin is sand.
 *   The thickest of the three, in whole quanta (ROCK_MIN and thinner dropped). Then no rock
 *   surface may stand higher over a neighbour's ground (rocks included) than d·ROCK_HOLD_SLOPE
 *   (40°, d = 1 or √2 m): passes in a fixed order thin the columns that do until none does.
 *   The stabilizer lets rocks rest at 42°, so it leaves them where they are, save where a
 *   ring estimate was off (tested: about 1 % of the rocks move). Cost: the ring's tops, extra
 *   lattice nodes and these passes, about +8 % of a chunk's generation.
 *
 * Lakes (ours; issue 15: "generation should make some lakes in basins"). A lattice of cells
 * lake_spacing metres wide holds at most one candidate site each, kept when a hash of (seed,
 * cell) says so (lake_probability): a bowl of radius r_b (hashed in the radius range), centred
 * where the hash puts it so that its whole circle of influence, radius R, stays inside the cell
 * — so a point is touched by its own cell's site alone, and a site is a pure function of (params,
 * cell): any chunk, any thread, finds the same one. The lake level is
 *     L = min over LAKE_RIM_SAMPLES points on the circle of radius R of G − LAKE_RIM_MARGIN,
 * G the natural macro ground; the site is dropped unless L ≥ sea_level + LAKE_MIN_ABOVE_SEA
 * and the centre's G ≤ L + LAKE_MAX_CENTRE (no craters on hilltops). Inside R the macro ground
 * is replaced by a designed basin, radius r from the centre, P = L + 1:
 *     r < r_b             P − (D + 1)·(1 − r²/r_b²)²      the bowl, L − D at the centre
 *     r_b ≤ r < r_p       P + 0.15·(r − r_b)             a shore, r_p = r_b + 2A + 6
 *     r_p ≤ r < R         S + s·(G − S)                  back to the land, s = smoothstep
 * (A the overhang shear, D = min(lake_depth, L − sea_level − 1), R = r_p + max(32 m, r_b), S the
 * shore's height at r_p). Water fills the top air run of
 * every column within r_w = r_b + A + 2 of the centre whose highest solid lies below L, up to L.
 * Why the water is held: a column's top is G' at a point at most A (the shear) plus a bilinear
 * cell from it, so every column with r in [r_w, r_w + 1.5] — the neighbours of the water circle
 * — reads only the shore (r_b − ½ … r_p) and stands at P or above, P > L; caves are kept under the surface within R (their
 * openings are off there, as under the sea). The clipmap's G (terrain__ground_row_spaced) has
 * the basins too, down to 8 m spacing (coarser levels draw the natural ground: a lake is a few
 * texels there, and the sites' rims would cost more than the row). A site costs 33 samples of
 * G; a chunk keeps the sites its grid met, and the clipmap's rows share a per-thread cache
 * (128² texels at 4 or 8 m: about +25 % over the natural ground; a generated chunk: no
 * difference measurable under load).
 *
 * Determinism: everything is a function of (params, coord), computed in the same order on any
 * thread; no shared state, no RNG. The G grid and the coarse lattice sit on world-aligned
 * positions (multiples of 1 m, and of 4 m and 2 m), so neighbouring chunks see the same values
 * at their shared border up to float rounding (a lattice node's y is y₀ + j·dy from each
 * chunk's own y₀), which keeps columns continuous across chunk borders.
 */
#include "terrain/data/terrain_data_internal.h"

#include "core/core.h"
#include "core/core_lanes.h"

#include <float.h>
#include <math.h>
#include <string.h>

#define COARSE 4                                   /* metres between coarse noise nodes in x, z */
#define COARSE_Y 2                                 /* and in y (the fields vary faster along y) */
#define COARSE_NODES (TERRAIN_CHUNK_COLUMNS / COARSE + 1)
#define SAMPLE_STEP 1.0f                           /* metres between density samples in a column */
#define CAVE_OCTAVES 2
#define CAVE_GAIN 0.25f                            /* octave 2 adds wall detail, keeps tunnels whole */
#define MAX_PERTURBATION_OCTAVES 4
#define MAX_FIELDS (2 * MAX_PERTURBATION_OCTAVES + 2 * CAVE_OCTAVES)
#define DISPLACEMENT_Y_SQUEEZE 3.0f                /* u, w vary 3× faster along y (see above) */
#define CLIFF_STEP 0.1f                            /* terrace height, a fraction of the relief */
#define CLIFF_RISER 0.2f                           /* the part of a terrace step that rises */
#define CLIFF_WAVELENGTH 900.0f                    /* of the mask that says where cliffs are */
#define CAVE_Y_SQUEEZE 1.5f                        /* caves run flatter than they are tall */
#define CAVE_OPENING 0.3f                          /* caves reach 0.3·fade above the ground */
#define MAX_TRANSITIONS 256
#define LAKE_RIM_SAMPLES 32                        /* points on a site's rim for its level */
#define LAKE_RIM_MARGIN 2.0f                       /* metres the level stays under the rim */
#define LAKE_MIN_ABOVE_SEA 3.0f                    /* lakes lie at least this far above the sea */
#define LAKE_MAX_CENTRE 30.0f                      /* a centre higher above L is a hill: no lake */
#define LAKE_SHELF_EXTRA 6.0f                      /* r_p = r_b + 2A + this */
#define LAKE_SHORE_SLOPE 0.15f                     /* the shore's rise from P over the shelf */
#define LAKE_BLEND_MIN 32.0f                       /* metres from the shelf back to the land */
#define LAKE_CACHE 8                               /* sites remembered while a grid is made */
#define LAKE_SPACED_MAX 8.0f                       /* coarser clipmap grids skip the basins */
#define LATTICE_NODES (COARSE_NODES + 2)           /* one more node each side: the rock ring's */
#define ROCK_RING 4                                /* columns around the chunk whose tops rocks see */
#define ROCK_SIDE (TERRAIN_CHUNK_COLUMNS + 2 * ROCK_RING)
#define ROCK_HOLD_SLOPE 0.84f                      /* tan 40°: generated rock surfaces are never
                                                      steeper (the stabilizer's rocks hold 42°) */
#define TALUS_DEPTH 2.5f
#define TALUS_SLOPE 0.7f                           /* tan 35°: the wedge's surface from the foot */
#define TALUS_REACH 3                              /* columns from a foot: ROCK_RING − 1 */
#define FOOT_RISE 1.5f                             /* a neighbour this much higher a metre: a wall */
#define SCREE_DEPTH 1.0f
#define SCREE_MIN_SLOPE 0.58f                      /* tan 30°: sand holds 30–35° (000 §3.4) */
#define SCREE_WAVELENGTH 24.0f                     /* of the noise that makes scree patches */
#define LAKE_ROCKS_DEPTH 0.8f
#define ROCK_MIN 0.1f                              /* thinner rock layers are dropped */
#define ROCK_CLIP_PASSES 16
#define RING_LEVELS_AROUND 8.0f                    /* metres around the ring's G its lattice covers */
/* Positions reach the 2D noises as a world-aligned origin, a multiple of this many metres, and
 * float offsets from it; the noises split the origin into lattice cell and offset in double
 * (terrain__lattice_split). So G is as precise 10 000 km out as within a kilometre of the
 * origin, and a point's value depends on the point alone, not on where its row starts (the
 * clipmap's rows and a chunk's grid agree bit for bit). */
#define NOISE_ORIGIN_BLOCK 1024.0

terrain_generation_desc terrain_generation_defaults(uint64_t seed) {
    return (terrain_generation_desc){
        .seed = seed,
        .sea_level = 0.0f,
        /* Relief: about −80 m (sea floors) to +160 m (peaks) around 25 m, rarely +250 m. */
        .relief_height = 150.0f,
        .base_height = 25.0f,
        .relief_wavelength = 1200.0f,
        .lacunarity = 2.0f,
        .hurst = 0.85f,
        .relief_octaves = 10,
        .warp_strength = 1.0f,
        .vertical_perturbation = 4.0f,
        .horizontal_perturbation = 10.0f,
        .perturbation_wavelength = 48.0f,
        .perturbation_octaves = 2,
        .cave_threshold = 0.22f,
        .cave_wavelength = 64.0f,
        .cave_fade_height = 12.0f,
        .sand_max_slope = 0.3f,                    /* about 17° */
        .sand_depth = 1.5f,
        .lake_spacing = 400.0f,
        .lake_probability = 0.8f,
        .lake_radius_min = 24.0f,
        .lake_radius_max = 56.0f,
        .lake_depth = 6.0f,
        .talus_depth = TALUS_DEPTH,
        .scree_depth = SCREE_DEPTH,
        .scree_min_slope = SCREE_MIN_SLOPE,
        .lake_rocks_depth = LAKE_ROCKS_DEPTH,
    };
}

/* ---- the macro ground G ---------------------------------------------------------------- */

/* A lake site (header comment, "Lakes"); valid false for a cell without a lake. */
typedef struct lake_site {
    int64_t cell_x, cell_z;
    bool valid;
    double x, z;                          /* centre, world metres */
    float bowl, water, shelf, outer;      /* radii r_b, r_w, r_p, R */
    float level, depth;                   /* L, D */
} lake_site;

typedef struct lake_cache {
    lake_site sites[LAKE_CACHE];
    int count, next;
} lake_cache;

typedef struct ground_model {
    terrain__multifractal multifractal;
    uint32_t perturbation_seed;
    int perturbation_octaves;
    float inverse_relief_wavelength, inverse_perturbation_wavelength;
    float base, relief, vertical_perturbation, sea_level;
    uint32_t cliff_seed;
    /* Detail kept when G is sampled coarser than the columns (terrain__ground_row_spaced); all
     * exactly 1 for the generator, so multiplying by them changes no bit of its output. */
    float relief_scale;                                    /* Σ kept octave weights / Σ all */
    float perturbation_weight[MAX_PERTURBATION_OCTAVES];
    float cliff_weight;
    float full_octaves;                                    /* the generator's ν */
    /* Lakes: off when lake_spacing is 0 (or the grid is too coarse for them). */
    uint64_t lake_seed;
    float lake_spacing, lake_probability, lake_radius_min, lake_radius_max, lake_depth, lake_shear;
    lake_cache *lakes;                                     /* sites found so far, or NULL */
    uint64_t key;                                          /* terrain_generation_key: whose sites */
    double origin_block;                                   /* metres: NOISE_ORIGIN_BLOCK, wider
                                                              on coarse grids */
} ground_model;

static uint32_t field_seed(const terrain_generation_desc *p, uint64_t field) {
    return terrain__seed32(core_hash_combine(p->seed, field));
}

static int clamp_int(int v, int lo, int hi) {
    return v < lo ? lo : v > hi ? hi : v;
}

static float clampf(float v, float lo, float hi) {
    return v < lo ? lo : v > hi ? hi : v;
}

static float relief_wavelength(const terrain_generation_desc *p) {
    return p->relief_wavelength > 1.0f ? p->relief_wavelength : 1.0f;
}

/* 004 §4.1: the octave count ν from the sampling spacing σ, the last octave weighted by frac(ν).
 * The paper's ν = −log σ / (H log r) measures σ against the octaves' amplitudes (r^−kH), which
 * ties the count to relief_height: a 600 m relief sampled every metre would sum octaves 1.2 m
 * long, finer than the samples can carry (aliasing), and an 8 m clipmap texel would get octaves
 * of 9 m. Our reading measures σ against their wavelengths, λ·r^−k: ν = log(λ / 4σ) / log r, at
 * most relief_octaves. Every octave summed (indices below ⌈ν⌉) then spans OCTAVE_MIN_SAMPLES
 * samples or more, whatever the relief: the last fades in as its wavelength grows from 4 to 8
 * samples (r = 2), the others span 8 or more. Four, not Nyquist's two, as for every noise this
 * file interpolates (header comment, step 3): the ground between samples is linear (bilinear G,
 * the clipmap's triangles), and octaves of 2–4 samples drawn that way left cracks between the
 * clipmap's levels (a render test saw sky through the ground at 2) and tipped more generated
 * rocks over (the stabilizer moved 2.0 % of them, 1.2 % before). */
#define OCTAVE_MIN_SAMPLES 4.0f

static float relief_octaves(const terrain_generation_desc *p, float lacunarity, float spacing) {
    /* terrain__multifractal_octaves(r, H = 1, s) is log s / −log r, clamped to [1, max]. */
    return terrain__multifractal_octaves(lacunarity, 1.0f, OCTAVE_MIN_SAMPLES * spacing / relief_wavelength(p),
                                         clamp_int(p->relief_octaves, 1, 16));
}

static ground_model ground_model_make(const terrain_generation_desc *p) {
    ground_model g;
    float lacunarity = p->lacunarity > 1.01f ? p->lacunarity : 2.0f;
    float hurst = p->hurst > 0.01f ? p->hurst : 0.85f;
    float relief = p->relief_height > 0.0f ? p->relief_height : 0.0f;
    float octaves = relief_octaves(p, lacunarity, TERRAIN_COLUMN_SIZE);   /* the columns' spacing */
    g.multifractal = (terrain__multifractal){ field_seed(p, 1), lacunarity, hurst, octaves, p->warp_strength };
    g.perturbation_seed = field_seed(p, 2);
    g.perturbation_octaves = clamp_int(p->perturbation_octaves, 1, MAX_PERTURBATION_OCTAVES);
    g.inverse_relief_wavelength = 1.0f / relief_wavelength(p);
    g.inverse_perturbation_wavelength =
        1.0f / (p->perturbation_wavelength > 1.0f ? p->perturbation_wavelength : 1.0f);
    g.base = p->base_height;
    g.relief = relief;
    g.vertical_perturbation = p->vertical_perturbation;
    g.cliff_seed = field_seed(p, 3);
    g.sea_level = p->sea_level;
    g.relief_scale = 1.0f;
    for (int k = 0; k < MAX_PERTURBATION_OCTAVES; k++) g.perturbation_weight[k] = 1.0f;
    g.cliff_weight = 1.0f;
    g.full_octaves = octaves;
    g.lake_seed = core_hash_combine(p->seed, 0x6c616b6573ull /* "lakes" */);
    g.lake_spacing = p->lake_spacing > 0.0f && isfinite(p->lake_spacing) ? p->lake_spacing : 0.0f;
    g.lake_probability = clampf(p->lake_probability, 0.0f, 1.0f);
    g.lake_radius_min = clampf(p->lake_radius_min, 1.0f, 1000.0f);
    g.lake_radius_max = clampf(p->lake_radius_max, g.lake_radius_min, 1000.0f);
    g.lake_depth = clampf(p->lake_depth, 0.0f, 200.0f);
    g.lake_shear = clampf(p->horizontal_perturbation, 0.0f, 64.0f);
    g.lakes = NULL;
    g.key = terrain_generation_key(p);
    g.origin_block = NOISE_ORIGIN_BLOCK;
    return g;
}

#define GROUND_ROW_MAX 256

/* ground_row_natural for points whose origin block starts at `origin`. */
static void ground_row_from(const ground_model *g, double origin, const double *xs, double z, int count, float *out) {
    float relief_x[GROUND_ROW_MAX] = { 0 }, relief[GROUND_ROW_MAX];
    float perturbation_x[GROUND_ROW_MAX] = { 0 }, perturbation[GROUND_ROW_MAX], octave[GROUND_ROW_MAX];
    for (int j = 0; j < count; j++) {
        relief_x[j] = (float)((xs[j] - origin) * g->inverse_relief_wavelength);
        perturbation_x[j] = (float)((xs[j] - origin) * g->inverse_perturbation_wavelength);
        perturbation[j] = 0.0f;
    }
    terrain__multifractal2_row(&g->multifractal, origin * g->inverse_relief_wavelength, relief_x,
                               z * g->inverse_relief_wavelength, count, relief);
    /* 002 §3.1.3.1: the y perturbation, a fractal sampled at y = 0, i.e. a height map. */
    double px = origin * g->inverse_perturbation_wavelength, pz = z * g->inverse_perturbation_wavelength;
    float amplitude = 1.0f, total = 0.0f, scale = 1.0f;
    for (int k = 0; k < g->perturbation_octaves; k++) {
        float weight = amplitude * g->perturbation_weight[k];
        if (weight > 0.0f) {
            terrain__noise2_row(g->perturbation_seed + (uint32_t)k * 0x9e3779b9u, px * scale, perturbation_x, scale,
                                pz * scale, count, octave);
            for (int j = 0; j < count; j++) perturbation[j] += weight * octave[j];
        }
        total += amplitude;
        amplitude *= 0.5f;
        scale *= 2.0f;
    }
    /* Where cliffs are: a low-frequency mask, 0 over about half the land. */
    float cliff_x[GROUND_ROW_MAX], cliffs[GROUND_ROW_MAX];
    for (int j = 0; j < count; j++) cliff_x[j] = (float)((xs[j] - origin) * (1.0 / CLIFF_WAVELENGTH));
    terrain__noise2_row(g->cliff_seed, origin * (1.0 / CLIFF_WAVELENGTH), cliff_x, 1.0f, z * (1.0 / CLIFF_WAVELENGTH), count,
                        cliffs);
    for (int j = 0; j < count; j++) {
        /* The normalised multifractal spans about ±0.4 (1st–99th percentile); 2.5 maps that
         * onto ±1. The shape keeps slope 0.6 at m = 0 on both sides but makes the highs convex
         * (m·(0.6 + 0.4m): peaks rise faster than valleys sink, lowlands stay gentle) and the
         * lows linear (seas no deeper than 0.6·relief for the usual range). */
        float m = 2.5f * (relief[j] * g->relief_scale);
        float shaped = m > 0.0f ? m * (0.6f + 0.4f * m) : 0.6f * m;
        float macro = g->base + g->relief * shaped;
        /* Cliffs: terraces of CLIFF_STEP·relief metres (15 m by default), each riser a quintic fade over the middle
         * CLIFF_RISER of the step (flat benches, risers up to 1.875 / CLIFF_RISER times the
         * slope around them), blended in by the mask.
         * The shear of the overhang displacement turns steep risers into overhangs. Only
         * above the sea: under water the relief stays smooth. */
        float strength = clampf(2.0f * cliffs[j] + 0.1f, 0.0f, 1.0f) * clampf(macro - g->sea_level, 0.0f, 8.0f) * 0.125f *
                         g->cliff_weight;
        float step = CLIFF_STEP * g->relief;
        if (step < 0.5f) strength = 0.0f, step = 1.0f;   /* no relief, no cliffs */
        float steps = macro / step, bench = floorf(steps);
        float rise = clampf((steps - bench - 0.5f) * (1.0f / CLIFF_RISER) + 0.5f, 0.0f, 1.0f);
        rise = rise * rise * rise * (rise * (rise * 6.0f - 15.0f) + 10.0f);
        float terraced = (bench + rise) * step;
        macro += strength * (terraced - macro);
        float h = macro + g->vertical_perturbation * perturbation[j] / total;
        /* Keep every height well inside what a column can hold above the floor. */
        out[j] = clampf(h, TERRAIN_FLOOR_Y + 16.0f, TERRAIN_FLOOR_Y + 4000.0f);
    }
}

/* G without lakes at (xs[j], z) for j < count (count ≤ GROUND_ROW_MAX): runs of points in one
 * origin block at a time. */
static void ground_row_natural(const ground_model *g, const double *xs, double z, int count, float *out) {
    for (int start = 0, end; start < count; start = end) {
        double origin = floor(xs[start] / g->origin_block) * g->origin_block;
        for (end = start + 1; end < count && floor(xs[end] / g->origin_block) * g->origin_block == origin; end++) {}
        ground_row_from(g, origin, xs + start, z, end - start, out + start);
    }
}

/* ---- lakes (header comment, "Lakes") ------------------------------------------------------ */

static float hash_unit(uint64_t h, int which) {
    return (float)((h >> (which * 21)) & 0x1fffff) * (1.0f / 2097152.0f);
}

/* The site of lattice cell (cx, cz), its level from the natural ground at full detail. */
static lake_site lake_site_make(const ground_model *g, int64_t cx, int64_t cz) {
    lake_site s = { .cell_x = cx, .cell_z = cz };
    uint64_t h = core_hash_combine(core_hash_combine(g->lake_seed, (uint64_t)cx), (uint64_t)cz);
    uint64_t h2 = core_hash_u64(h);
    if (hash_unit(h, 0) >= g->lake_probability) return s;
    float spacing = g->lake_spacing;
    s.bowl = g->lake_radius_min + (g->lake_radius_max - g->lake_radius_min) * hash_unit(h, 1);
    s.water = s.bowl + g->lake_shear + 2.0f;
    s.shelf = s.bowl + 2.0f * g->lake_shear + LAKE_SHELF_EXTRA;
    s.outer = s.shelf + CORE_MAX(LAKE_BLEND_MIN, s.bowl);
    if (2.0f * s.outer >= spacing) return s;                /* it would not fit in its cell */
    s.x = (double)cx * spacing + s.outer + (double)(hash_unit(h, 2) * (spacing - 2.0f * s.outer));
    s.z = (double)cz * spacing + s.outer + (double)(hash_unit(h2, 0) * (spacing - 2.0f * s.outer));
    ground_model full = *g;                                 /* the generator's own G */
    full.multifractal.octaves = g->full_octaves;
    full.relief_scale = full.cliff_weight = 1.0f;
    for (int k = 0; k < MAX_PERTURBATION_OCTAVES; k++) full.perturbation_weight[k] = 1.0f;
    float lowest = INFINITY, centre;
    for (int n = 0; n < LAKE_RIM_SAMPLES; n++) {
        double angle = 2.0 * 3.14159265358979323846 * n / LAKE_RIM_SAMPLES, x = s.x + s.outer * cos(angle), rim;
        float height;
        rim = s.z + s.outer * sin(angle);
        ground_row_natural(&full, &x, rim, 1, &height);
        lowest = CORE_MIN(lowest, height);
    }
    ground_row_natural(&full, &s.x, s.z, 1, &centre);
    s.level = lowest - LAKE_RIM_MARGIN;
    s.depth = CORE_MIN(g->lake_depth, s.level - g->sea_level - 1.0f);
    s.valid = s.level >= g->sea_level + LAKE_MIN_ABOVE_SEA && centre <= s.level + LAKE_MAX_CENTRE && s.depth >= 1.0f;
    return s;
}

static int64_t floor_to_cell(double v, float spacing) {
    return (int64_t)floor(v / (double)spacing);
}

/* The valid site whose circle of influence holds (x, z), or NULL. */
static const lake_site *lake_site_at(const ground_model *g, lake_cache *cache, double x, double z) {
    int64_t cx = floor_to_cell(x, g->lake_spacing), cz = floor_to_cell(z, g->lake_spacing);
    const lake_site *s = NULL;
    for (int n = 0; n < cache->count && !s; n++)
        if (cache->sites[n].cell_x == cx && cache->sites[n].cell_z == cz) s = &cache->sites[n];
    if (!s) {
        lake_site *slot = &cache->sites[cache->next];
        *slot = lake_site_make(g, cx, cz);
        cache->next = (cache->next + 1) % LAKE_CACHE;
        cache->count = CORE_MIN(cache->count + 1, LAKE_CACHE);
        s = slot;
    }
    if (!s->valid) return NULL;
    double dx = x - s->x, dz = z - s->z;
    return dx * dx + dz * dz < (double)s->outer * (double)s->outer ? s : NULL;
}

/* The basin's ground at distance r from the centre, over natural ground `natural`. */
static float lake_shape(const lake_site *s, float r, float natural) {
    float plateau = s->level + 1.0f;
    if (r < s->bowl) {
        float t = 1.0f - (r * r) / (s->bowl * s->bowl);
        return plateau - (s->depth + 1.0f) * t * t;
    }
    if (r < s->shelf) return plateau + LAKE_SHORE_SLOPE * (r - s->bowl);
    float shore = plateau + LAKE_SHORE_SLOPE * (s->shelf - s->bowl);
    float t = clampf((r - s->shelf) / (s->outer - s->shelf), 0.0f, 1.0f);
    return shore + t * t * (3.0f - 2.0f * t) * (natural - shore);
}

/* Sites are a pure function of (params, cell), so callers without a cache of their own (the
 * clipmap's rows, one call each) share one per thread, tagged with the parameters' key: the next
 * row meets the same few cells, whose rims need not be sampled again. */
static lake_cache *lake_thread_cache(uint64_t key) {
    static _Thread_local lake_cache cache;
    static _Thread_local uint64_t cache_key;
    if (cache_key != key || cache.count == 0) cache = (lake_cache){ .count = 0 }, cache_key = key;
    return &cache;
}

/* G: the natural ground with the lakes' basins; with `levels`, also the level of the lake whose
 * water circle holds each point (lake_level_at's), TERRAIN__NO_LAKE elsewhere. */
static void ground_row_lakes(const ground_model *g, const double *xs, double z, int count, float *out, float *levels) {
    ground_row_natural(g, xs, z, count, out);
    if (levels)
        for (int j = 0; j < count; j++) levels[j] = TERRAIN__NO_LAKE;
    if (!(g->lake_spacing > 0.0f)) return;
    lake_cache *cache = g->lakes ? g->lakes : lake_thread_cache(g->key);
    for (int j = 0; j < count; j++) {
        const lake_site *s = lake_site_at(g, cache, xs[j], z);
        if (!s) continue;
        float r = (float)hypot(xs[j] - s->x, z - s->z);
        out[j] = lake_shape(s, r, out[j]);
        if (levels && r < s->water) levels[j] = s->level;
    }
}

static void ground_row(const ground_model *g, const double *xs, double z, int count, float *out) {
    ground_row_lakes(g, xs, z, count, out, NULL);
}

/* The lake level over column centre (x, z) when it lies in a lake's water circle, else NAN;
 * *basin is how much of the designed basin the ground there is: 1 out to the shore's end, falling
 * as the ground returns to the land (lake_shape's smoothstep), 0 outside the site's circle. */
static float lake_level_at(const ground_model *g, double x, double z, float *basin) {
    *basin = 0.0f;
    if (!(g->lake_spacing > 0.0f)) return NAN;
    const lake_site *s = lake_site_at(g, g->lakes ? g->lakes : lake_thread_cache(g->key), x, z);
    if (!s) return NAN;
    float r = (float)hypot(x - s->x, z - s->z);
    float t = clampf((r - s->shelf) / (s->outer - s->shelf), 0.0f, 1.0f);
    *basin = fmaxf(1.0f - t * t * (3.0f - 2.0f * t), FLT_MIN);   /* > 0 anywhere inside the circle */
    return r < s->water ? s->level : NAN;
}

float terrain__ground_height(const terrain_generation_desc *params, double x, double z) {
    ground_model g = ground_model_make(params);
    float h;
    ground_row(&g, &x, z, 1, &h);
    return h;
}

/* ---- G sampled coarsely: the far terrain's clipmap (002 §3.2, 004 §4.1) ------------------- */

/* Terraces fade out between these sample spacings: a riser is CLIFF_RISER·CLIFF_STEP·relief
 * (3 m by default) tall and 10–30 m wide on the usual 0.1–0.3 slopes, so 4 m samples still
 * draw it and 16 m samples would only alias it into a staircase of random steps. */
#define CLIFF_FULL_SPACING 4.0f
#define CLIFF_GONE_SPACING 16.0f

/* Σ of the multifractal's octave weights r^(−kH), the last weighted by frac(ν) (004 §4). */
static float multifractal_weight_sum(const terrain__multifractal *mf) {
    float r0 = powf(mf->lacunarity, -mf->hurst), amplitude = 1.0f, total = 0.0f;
    int full = CORE_MIN((int)mf->octaves, 16);
    for (int k = 0; k < full; k++, amplitude *= r0) total += amplitude;
    return total + (mf->octaves - (float)full) * amplitude;
}

/* The generator's model with the detail a grid of `spacing` metres cannot carry taken out. */
static ground_model ground_model_spaced(const terrain_generation_desc *p, float spacing) {
    ground_model g = ground_model_make(p);
    if (!(spacing > TERRAIN_COLUMN_SIZE)) return g;        /* the columns' own G, bit for bit */
    /* Rows of 64 points or more between origins (short runs cost the SIMD rows their speed); the
     * relief octaves kept have wavelengths of 4 spacings or more (relief_octaves), so an offset
     * of up to 64 spacings is a few dozen cells of the finest: float keeps 10⁻⁵ of a cell. */
    g.origin_block = fmax(NOISE_ORIGIN_BLOCK, 64.0 * spacing);
    float full_octaves = g.multifractal.octaves;
    /* 004 §4.1, as the generator does for its 1 m columns (relief_octaves). */
    g.multifractal.octaves = relief_octaves(p, g.multifractal.lacunarity, spacing);
    /* The multifractal normalises by the weights of the octaves it sums; rescale so that the
     * octaves dropped are simply missing (a low-pass of G) rather than the kept ones louder. */
    if (g.multifractal.octaves != full_octaves) {
        terrain__multifractal all = g.multifractal;
        all.octaves = full_octaves;
        g.relief_scale = multifractal_weight_sum(&g.multifractal) / multifractal_weight_sum(&all);
    }
    /* The y perturbation's octave k has wavelength λ/2^k: whole while it spans 4 samples or
     * more, gone at 2 (Nyquist), linear between. */
    float wavelength = 1.0f / g.inverse_perturbation_wavelength;
    for (int k = 0; k < g.perturbation_octaves; k++)
        g.perturbation_weight[k] = clampf(ldexpf(wavelength, -k) / (2.0f * spacing) - 1.0f, 0.0f, 1.0f);
    g.cliff_weight = clampf((CLIFF_GONE_SPACING - spacing) / (CLIFF_GONE_SPACING - CLIFF_FULL_SPACING), 0.0f, 1.0f);
    if (spacing > LAKE_SPACED_MAX) g.lake_spacing = 0.0f;   /* header comment, "Lakes" */
    return g;
}

void terrain__ground_row_spaced(const terrain_generation_desc *params, double x0, double dx, double z, int count,
                                float spacing, float *out, float *lakes) {
    ground_model g = ground_model_spaced(params, spacing);
    double xs[GROUND_ROW_MAX];
    for (int done = 0; done < count; done += GROUND_ROW_MAX) {
        int n = CORE_MIN(count - done, GROUND_ROW_MAX);
        for (int j = 0; j < n; j++) xs[j] = x0 + (double)(done + j) * dx;
        ground_row_lakes(&g, xs, z, n, out + done, lakes ? lakes + done : NULL);
    }
}

void terrain__lake_row_spaced(const terrain_generation_desc *params, double x0, double dx, double z, int count,
                              float spacing, float *out) {
    float ground[GROUND_ROW_MAX];
    for (int done = 0; done < count; done += GROUND_ROW_MAX) {
        int n = CORE_MIN(count - done, GROUND_ROW_MAX);
        terrain__ground_row_spaced(params, x0 + (double)done * dx, dx, z, n, spacing, ground, out + done);
    }
}

float terrain__ground_octaves(const terrain_generation_desc *params, float spacing) {
    return ground_model_spaced(params, spacing).multifractal.octaves;
}

/* ---- one chunk ------------------------------------------------------------------------- */

typedef struct chunk_gen {
    const terrain_generation_desc *params;
    ground_model model;
    double x0, z0;                        /* world position of the chunk's corner */
    float displacement;                   /* A, metres */
    int margin;                           /* G grid columns beyond the chunk on each side */
    int ground_size;                      /* G grid side: N + 2·margin */
    float *heights;                       /* G at column centres, [(k + margin)·size + i + margin] */
    float *reach_min, *reach_max;         /* min/max of G within reach of each column of the chunk
                                             and its rock ring, [reach_index(i, k)] */
    /* Coarse lattice: node (a, c, level) at world (x0 + 4a, y_base + 2·level, z0 + 4c), a and c
     * from −1 (the rock ring's nodes: u and w only, at ring_levels) to COARSE_NODES. */
    int fields;                           /* u octaves, w octaves, cave 1 octaves, cave 2 octaves */
    int levels;
    float y_base;
    float *coarse;                        /* [((field·L + c + 1)·L + a + 1)·levels + level], L
                                             LATTICE_NODES */
    int ring_level_lo, ring_level_hi;     /* the ring's nodes hold these levels */
    uint32_t field_seeds[MAX_FIELDS];
    float field_frequency[MAX_FIELDS];    /* horizontal, cycles per metre */
    float field_y_squeeze[MAX_FIELDS];
    float field_weight[MAX_FIELDS];       /* displacement octaves' normalised amplitudes */
    lake_cache lakes;                     /* the sites the chunk's grid met */
    float *lake_levels;                   /* per column: the lake level over it, or NAN */
    float *basin;                         /* per column: lake_level_at's basin share, > 0 inside a
                                             lake's circle of influence */
} chunk_gen;

/* Columns of the chunk and its rock ring: i, k from −ROCK_RING to N + ROCK_RING − 1. */
static inline int reach_index(int i, int k) {
    return (k + ROCK_RING) * ROCK_SIDE + i + ROCK_RING;
}

static void ground_grid(chunk_gen *g) {
    int size = g->ground_size;
    double xs[GROUND_ROW_MAX];
    for (int i = 0; i < size; i++) xs[i] = g->x0 + (double)(i - g->margin) + 0.5;
    for (int k = 0; k < size; k++)
        ground_row(&g->model, xs, g->z0 + (double)(k - g->margin) + 0.5, size, g->heights + (size_t)k * size);
}

/* Min and max of G over the square of radius `radius` around each column of the chunk and its
 * rock ring: separable. The ring's squares are cut to the grid (their tops are estimates). */
static void ground_reach(chunk_gen *g, int radius) {
    int size = g->ground_size, n = ROCK_SIDE, m = g->margin - ROCK_RING;
    float *row_min = core_alloc((size_t)size * n * sizeof(float));
    float *row_max = core_alloc((size_t)size * n * sizeof(float));
    for (int k = 0; k < size; k++) {
        for (int i = 0; i < n; i++) {
            float lo = INFINITY, hi = -INFINITY;
            int from = CORE_MAX(i + m - radius, 0), to = CORE_MIN(i + m + radius, size - 1);
            for (int x = from; x <= to; x++) {
                float v = g->heights[k * size + x];
                lo = v < lo ? v : lo;
                hi = v > hi ? v : hi;
            }
            row_min[k * n + i] = lo;
            row_max[k * n + i] = hi;
        }
    }
    for (int k = 0; k < n; k++) {
        int from = CORE_MAX(k + m - radius, 0), to = CORE_MIN(k + m + radius, size - 1);
        for (int i = 0; i < n; i++) {
            float lo = INFINITY, hi = -INFINITY;
            for (int z = from; z <= to; z++) {
                lo = CORE_MIN(lo, row_min[z * n + i]);
                hi = CORE_MAX(hi, row_max[z * n + i]);
            }
            g->reach_min[k * n + i] = lo;
            g->reach_max[k * n + i] = hi;
        }
    }
    core_free(row_min, (size_t)size * n * sizeof(float));
    core_free(row_max, (size_t)size * n * sizeof(float));
}

static float cave_depth(const terrain_generation_desc *p) {
    /* The band below the ground where caves live: the fade, then one and a half cave
     * wavelengths (about 110 m by default: deeper caves cost time and nobody sees them). */
    return p->cave_fade_height + 1.5f * p->cave_wavelength;
}

static bool caves_enabled(const terrain_generation_desc *p) {
    return p->cave_threshold > 0.0f && p->cave_wavelength > 0.0f;
}

/* The y range a column samples: from the lowest point where a cave or the ground's surface can
 * be to the highest point where the ground can be. */
static void column_range(const chunk_gen *g, int i, int k, float *lo, float *hi) {
    float ground = g->heights[(k + g->margin) * g->ground_size + i + g->margin];
    float bottom = g->reach_min[reach_index(i, k)] - SAMPLE_STEP;
    if (caves_enabled(g->params)) bottom = CORE_MIN(bottom, ground - cave_depth(g->params));
    *lo = CORE_MAX(bottom, TERRAIN_FLOOR_Y + 2.0f);
    *hi = g->reach_max[reach_index(i, k)] + SAMPLE_STEP;
}

static void coarse_setup(chunk_gen *g) {
    const terrain_generation_desc *p = g->params;
    int f = 0;
    int octaves = g->model.perturbation_octaves;
    float total = 0.0f;
    for (int o = 0; o < octaves; o++) total += ldexpf(1.0f, -o);
    for (int axis = 0; axis < 2; axis++) {         /* u (x displacement), w (z displacement) */
        for (int o = 0; o < octaves; o++, f++) {
            g->field_seeds[f] = field_seed(p, 16 + (uint64_t)axis * 8 + (uint64_t)o);
            g->field_frequency[f] = g->model.inverse_perturbation_wavelength * ldexpf(1.0f, o);
            g->field_y_squeeze[f] = DISPLACEMENT_Y_SQUEEZE;
            g->field_weight[f] = ldexpf(1.0f, -o) / total;
        }
    }
    if (caves_enabled(p)) {
        for (int cave = 0; cave < 2; cave++) {
            for (int o = 0; o < CAVE_OCTAVES; o++, f++) {
                g->field_seeds[f] = field_seed(p, 64 + (uint64_t)cave * 8 + (uint64_t)o);
                g->field_frequency[f] = ldexpf(1.0f, o) / p->cave_wavelength;
                g->field_y_squeeze[f] = CAVE_Y_SQUEEZE;
                g->field_weight[f] = 1.0f;
            }
        }
    }
    g->fields = f;
}

static size_t lattice_floats(const chunk_gen *g) {
    return (size_t)g->fields * LATTICE_NODES * LATTICE_NODES * (size_t)g->levels;
}

static const float *lattice_node(const chunk_gen *g, int f, int a, int c) {
    return g->coarse + (((size_t)f * LATTICE_NODES + (size_t)(c + 1)) * LATTICE_NODES + (size_t)(a + 1)) * g->levels;
}

/* The caves' fields at the chunk's nodes, each looked up where the ground's displacement moves
 * that node: 002 §3.1.3.2 perturbs the cave map "with the use of the perturbing techniques covered
 * in the previous section" (Fig. 11), so the cave map at p is C(p + A·(u(p), 0, w(p))), with the
 * very u, w (lattice nodes, weights) that ground_density applies to G. Interpolating those node
 * values as before gives a cave map bent by the same field as the surface around it: a tunnel
 * follows an overhang's shear instead of cutting straight through it. Fields [0, displacement_fields)
 * must already hold the nodes' u and w. */
static void cave_lattice(chunk_gen *g, int displacement_fields) {
    int levels = g->levels, octaves = g->model.perturbation_octaves;
    float a = g->displacement;
    size_t bytes = (size_t)levels * sizeof(float);
    float *dx = core_alloc(bytes), *dz = core_alloc(bytes), *xs = core_alloc(bytes), *ys = core_alloc(bytes),
          *zs = core_alloc(bytes);
    for (int c = 0; c < COARSE_NODES; c++) {
        for (int n = 0; n < COARSE_NODES; n++) {
            for (int l = 0; l < levels; l++) dx[l] = dz[l] = 0.0f;
            for (int o = 0; o < octaves; o++) {
                const float *u = lattice_node(g, o, n, c), *w = lattice_node(g, octaves + o, n, c);
                float weight = g->field_weight[o];
                for (int l = 0; l < levels; l++) dx[l] += weight * u[l], dz[l] += weight * w[l];
            }
            for (int f = displacement_fields; f < g->fields; f++) {
                float frequency = g->field_frequency[f];
                float dy = COARSE_Y * frequency * g->field_y_squeeze[f];
                float y0 = g->y_base * frequency * g->field_y_squeeze[f];
                /* The node in double, the displacement as a float offset from it: the noise splits
                 * the node into lattice cell and offset (terrain__lattice_split), as far out as near. */
                double x = (g->x0 + (double)(n * COARSE)) * frequency, z = (g->z0 + (double)(c * COARSE)) * frequency;
                for (int l = 0; l < levels; l++) {
                    xs[l] = a * dx[l] * frequency;
                    ys[l] = y0 + (float)l * dy;
                    zs[l] = a * dz[l] * frequency;
                }
                terrain__noise3_points(g->field_seeds[f], x, z, xs, ys, zs, levels, (float *)lattice_node(g, f, n, c));
            }
        }
    }
    core_free(dx, bytes);
    core_free(dz, bytes);
    core_free(xs, bytes);
    core_free(ys, bytes);
    core_free(zs, bytes);
}

/* The chunk's nodes over every level; the ring's (a or c = −1 or COARSE_NODES) only for the
 * displacement fields and over [ring_lo, ring_hi]: the ring's tops need nothing else. */
static void coarse_lattice(chunk_gen *g, float y_lo, float y_hi, float ring_lo, float ring_hi) {
    g->y_base = floorf(y_lo / COARSE_Y) * COARSE_Y;
    g->levels = (int)ceilf((y_hi - g->y_base) / COARSE_Y) + 2;
    g->ring_level_lo = clamp_int((int)floorf((ring_lo - g->y_base) / COARSE_Y), 0, g->levels - 1);
    g->ring_level_hi = clamp_int((int)ceilf((ring_hi - g->y_base) / COARSE_Y) + 1, 0, g->levels - 1);
    g->coarse = core_calloc(lattice_floats(g), sizeof(float));
    int ring_fields = 2 * g->model.perturbation_octaves, ring_count = g->ring_level_hi - g->ring_level_lo + 1;
    /* The displacement fields first (they come first): the caves' lookups read them. */
    for (int f = 0; f < ring_fields; f++) {
        float frequency = g->field_frequency[f];
        float dy = COARSE_Y * frequency * g->field_y_squeeze[f];
        float y0 = g->y_base * frequency * g->field_y_squeeze[f];
        for (int c = -1; c <= COARSE_NODES; c++) {
            double z = (g->z0 + (double)(c * COARSE)) * frequency;   /* in double: the noise splits it */
            for (int a = -1; a <= COARSE_NODES; a++) {
                double x = (g->x0 + (double)(a * COARSE)) * frequency;
                float *out = (float *)lattice_node(g, f, a, c);
                if (a >= 0 && c >= 0 && a < COARSE_NODES && c < COARSE_NODES)
                    terrain__noise3_column(g->field_seeds[f], x, y0, dy, z, g->levels, out);
                else
                    terrain__noise3_column(g->field_seeds[f], x, y0 + (float)g->ring_level_lo * dy, dy, z, ring_count,
                                           out + g->ring_level_lo);
            }
        }
    }
    if (g->fields > ring_fields) cave_lattice(g, ring_fields);
}

/* ---- one column ------------------------------------------------------------------------ */

/* Bilinear interpolation of the first `fields` fields' coarse columns to the centre of column
 * (i, k) (a ring column too), over levels [l0, l1]. */
static void column_fields(const chunk_gen *g, int i, int k, int fields, int l0, int l1, float *out) {
    float ax = ((float)i + 0.5f) / COARSE, cz = ((float)k + 0.5f) / COARSE;
    int a = (int)floorf(ax), c = (int)floorf(cz);
    float tx = ax - (float)a, tz = cz - (float)c;
    float w00 = (1 - tx) * (1 - tz), w10 = tx * (1 - tz), w01 = (1 - tx) * tz, w11 = tx * tz;
    int levels = g->levels;
    const core_floats4 v00 = core_floats4_splat(w00), v10 = core_floats4_splat(w10), v01 = core_floats4_splat(w01),
                       v11 = core_floats4_splat(w11);
    for (int f = 0; f < fields; f++) {
        const float *p00 = lattice_node(g, f, a, c), *p10 = p00 + levels;
        const float *p01 = p00 + (size_t)LATTICE_NODES * levels, *p11 = p01 + levels;
        float *o = out + (size_t)f * levels;
        int l = l0;
        /* four levels at a time (GCC's vector types: SSE2 on any x86-64), the same sum in the
         * same order as one at a time: the same bits */
        for (; l + 3 <= l1; l += 4) {
            core_floats4 sum = v00 * core_floats4_load(p00 + l) + v10 * core_floats4_load(p10 + l) +
                               v01 * core_floats4_load(p01 + l) + v11 * core_floats4_load(p11 + l);
            core_floats4_store(o + l, sum);
        }
        for (; l <= l1; l++) o[l] = w00 * p00[l] + w10 * p10[l] + w01 * p01[l] + w11 * p11[l];
    }
}

static float ground_lookup(const chunk_gen *g, float gx, float gz) {
    /* Bilinear in the G grid; gx, gz in grid units (column centres at integers). */
    int size = g->ground_size;
    gx = clampf(gx, 0.0f, (float)(size - 1) - 1e-3f);
    gz = clampf(gz, 0.0f, (float)(size - 1) - 1e-3f);
    int i = (int)gx, k = (int)gz;
    float tx = gx - (float)i, tz = gz - (float)k;
    const float *row = g->heights + k * size + i;
    float a = row[0] + tx * (row[1] - row[0]);
    float b = row[size] + tx * (row[size + 1] - row[size]);
    return a + tz * (b - a);
}

/* Heights where solid and air alternate, bottom-up, starting in solid: even indices are tops
 * of solid runs, odd ones bottoms; the count is odd (the column ends in air). */
typedef struct column_layers {
    float transitions[MAX_TRANSITIONS];
    int count;
} column_layers;

/* What a column's density needs: its interpolated fields and bounds. */
typedef struct column_context {
    const chunk_gen *g;
    const float *u, *w, *cave1, *cave2;    /* [octave·levels + level] */
    float gx, gz;                          /* the column centre in G grid units */
    float reach_min;                       /* below this the ground part is surely solid */
    float cave_top, cave_bottom, fade;
    float threshold, cave_scale;
    int octaves, levels;
    bool caves;
} column_context;

static inline float ground_density(const column_context *c, int l, float t, float y) {
    /* The sideways displacement of the sample point (002 Fig. 8). */
    float du = 0.0f, dw = 0.0f;
    for (int o = 0; o < c->octaves; o++) {
        const float *uo = c->u + (size_t)o * c->levels, *wo = c->w + (size_t)o * c->levels;
        du += c->g->field_weight[o] * (uo[l] + t * (uo[l + 1] - uo[l]));
        dw += c->g->field_weight[o] * (wo[l] + t * (wo[l + 1] - wo[l]));
    }
    float a = c->g->displacement;
    return ground_lookup(c->g, c->gx + a * du, c->gz + a * dw) - y;
}

static inline bool in_cave_band(const column_context *c, float y) {
    return c->caves && y > c->cave_bottom && y < c->cave_top;
}

/* One of the caves' ridged fields (cave1 or cave2) at level l + t: its octaves interpolated. */
static inline float cave_ridged(const column_context *c, const float *field, int l, float t) {
    float n[CAVE_OCTAVES];
    for (int o = 0; o < CAVE_OCTAVES; o++) {
        const float *a = field + (size_t)o * c->levels;
        n[o] = a[l] + t * (a[l + 1] - a[l]);
    }
    return terrain__ridged_from_octaves(n, CAVE_OCTAVES, CAVE_GAIN);
}

/* 1 − threshold·attenuation at y: what R₁R₂ must exceed for a cave. Height attenuation
 * (002 §3.1.3.2): 0 above cave_top, full from fade below it, fading out again over the fade
 * above cave_bottom. */
static inline float cave_room(const column_context *c, float y) {
    float attenuation = clampf((c->cave_top - y) / c->fade, 0.0f, 1.0f) *
                        clampf((y - c->cave_bottom) / c->fade, 0.0f, 1.0f);
    return 1.0f - c->threshold * attenuation;
}

static inline float cave_density(const column_context *c, int l, float t, float y) {
    float ridges = cave_ridged(c, c->cave1, l, t) * cave_ridged(c, c->cave2, l, t);
    return (cave_room(c, y) - ridges) * c->cave_scale;
}

/* Whether cave_density(c, l, t, y) > 0, i.e. R₁R₂ < cave_room (cave_scale > 0), found from R₁
 * alone where it is already below: R₂ ≤ 1, so R₁R₂ ≤ R₁ (in floats too: the product rounds
 * monotonically). The same answer as the sign of cave_density, bit for bit. */
static inline bool cave_solid(const column_context *c, int l, float t, float y) {
    if (!(c->cave_scale > 0.0f)) return cave_density(c, l, t, y) > 0.0f;
    float room = cave_room(c, y), first = cave_ridged(c, c->cave1, l, t);
    return first < room || room - first * cave_ridged(c, c->cave2, l, t) > 0.0f;
}

/* The density at y, every part evaluated (for placing a crossing). */
static float density_exact(const column_context *c, float y) {
    float level = (y - c->g->y_base) * (1.0f / COARSE_Y);
    int l = (int)level;
    float t = level - (float)l;
    float d = ground_density(c, l, t, y);
    if (in_cave_band(c, y)) d = CORE_MIN(d, cave_density(c, l, t, y));
    return d;
}

/* The largest ridged value the interpolated octaves can reach between levels l and l + 1:
 * ridged_from_octaves grows as each |n| shrinks, and on a linear segment |n| is smallest at an
 * end, or 0 where the sign changes. */
static float ridged_bound(const float *n, int levels, int l) {
    float smallest[CAVE_OCTAVES];
    for (int o = 0; o < CAVE_OCTAVES; o++) {
        float a = n[(size_t)o * levels + l], b = n[(size_t)o * levels + l + 1];
        smallest[o] = (a > 0.0f) != (b > 0.0f) ? 0.0f : CORE_MIN(fabsf(a), fabsf(b));
    }
    return terrain__ridged_from_octaves(smallest, CAVE_OCTAVES, CAVE_GAIN);
}

/* ---- the caves' bounds, four segments at a time ----------------------------------------------
 * ridged_bound and the test of caves_possible in GCC's vector types (SSE2 on any x86-64): the
 * same operations in the same order as one segment at a time, so the same bits. */

/* terrain__ridged_from_octaves of CAVE_OCTAVES octaves, per lane. */
static inline core_floats4 ridged_lanes(const core_floats4 *n) {
    const core_floats4 zero = core_floats4_splat(0.0f), one = core_floats4_splat(1.0f), two = core_floats4_splat(2.0f);
    core_floats4 result = zero, total = zero, weight = one, amplitude = one;
    for (int k = 0; k < CAVE_OCTAVES; k++) {
        core_floats4 signal = one - core_floats4_abs(n[k]);
        signal *= signal * weight;
        weight = signal * two;
        weight = core_floats4_select(weight > one, one, weight);
        result += signal * amplitude;
        total += amplitude;
        amplitude *= core_floats4_splat(CAVE_GAIN);
    }
    return core_floats4_select(total > zero, result / total, zero);
}

/* ridged_bound of the segments l … l + 3 of one field's octaves. */
static inline core_floats4 ridged_bound_lanes(const float *n, int levels, int l) {
    core_floats4 smallest[CAVE_OCTAVES];
    for (int o = 0; o < CAVE_OCTAVES; o++) {
        core_floats4 a = core_floats4_load(n + (size_t)o * levels + l), b = core_floats4_load(n + (size_t)o * levels + l + 1);
        core_floats4 fa = core_floats4_abs(a), fb = core_floats4_abs(b);
        core_ints4 crosses = (a > core_floats4_splat(0.0f)) ^ (b > core_floats4_splat(0.0f));
        smallest[o] = core_floats4_select(crosses, core_floats4_splat(0.0f), core_floats4_select(fa < fb, fa, fb));
    }
    return ridged_lanes(smallest);
}

/* cave_possible[l] for the segments first … last of the column (l + 1 < levels): whether the
 * caves' two ridged fields can together pass the threshold anywhere in the segment. */
static void caves_possible(const column_context *c, int first, int last, bool *possible) {
    const float room = 1.0f - c->threshold;
    int l = first;
    for (; l + 3 <= last && l + 4 < c->levels; l += 4) {
        core_floats4 r1 = ridged_bound_lanes(c->cave1, c->levels, l), r2 = ridged_bound_lanes(c->cave2, c->levels, l);
        core_ints4 yes = (r1 * r2) > core_floats4_splat(room);
        for (int k = 0; k < 4; k++) possible[l + k] = yes[k] != 0;
    }
    for (; l <= last && l + 1 < c->levels; l++) {   /* the second bound only where the first leaves room: both are at most 1 */
        float r1 = ridged_bound(c->cave1, c->levels, l);
        possible[l] = r1 > room && r1 * ridged_bound(c->cave2, c->levels, l) > room;
    }
}

static void column_generate(const chunk_gen *g, int i, int k, const float *fields, bool *cave_possible,
                            column_layers *out) {
    const terrain_generation_desc *p = g->params;
    float y_lo, y_hi;
    column_range(g, i, k, &y_lo, &y_hi);
    float ground_here = g->heights[(k + g->margin) * g->ground_size + i + g->margin];
    column_context c = {
        .g = g, .gx = (float)(i + g->margin), .gz = (float)(k + g->margin),
        .reach_min = g->reach_min[reach_index(i, k)],
        .octaves = g->model.perturbation_octaves, .levels = g->levels, .caves = caves_enabled(p),
        .fade = p->cave_fade_height > 0.5f ? p->cave_fade_height : 0.5f,
        .threshold = p->cave_threshold,
        /* In metres, roughly, so that min() with the ground's part is balanced: R₁R₂ changes by
         * about 1 over a tenth of a cave wavelength. */
        .cave_scale = p->cave_wavelength * 0.1f,
    };
    c.u = fields;
    c.w = fields + (size_t)c.octaves * c.levels;
    c.cave1 = fields + (size_t)2 * c.octaves * c.levels;
    c.cave2 = c.cave1 + (size_t)CAVE_OCTAVES * c.levels;
    /* Caves open at the surface on land, never under the sea or in a lake's basin. */
    bool opening = ground_here > p->sea_level + 2.0f && !(g->basin[k * TERRAIN_CHUNK_COLUMNS + i] > 0.0f);
    c.cave_top = ground_here + (opening ? CAVE_OPENING * c.fade : -0.5f * c.fade);
    c.cave_bottom = ground_here - cave_depth(p);

    /* Segments of the coarse lattice where this column can have a cave at all. */
    int first_level = (int)((y_lo - g->y_base) * (1.0f / COARSE_Y));
    int last_level = (int)((y_hi + 2.0f * SAMPLE_STEP - g->y_base) * (1.0f / COARSE_Y));
    if (c.caves) caves_possible(&c, first_level, last_level, cave_possible);

    out->count = 0;
    bool solid = true;                    /* y_lo is below every surface */
    float previous_y = y_lo;
    int samples = (int)ceilf((y_hi - y_lo) / SAMPLE_STEP) + 1;
    for (int j = 0; j <= samples; j++) {
        float y = y_lo + (float)j * SAMPLE_STEP;
        float level = (y - g->y_base) * (1.0f / COARSE_Y);
        int l = (int)level;
        float t = level - (float)l;
        bool cave_here = in_cave_band(&c, y) && cave_possible[l];
        /* Only the sign matters here: solid where the ground's part and the cave's are both
         * positive (density = min of the two), the crossing placed below from both in full. */
        bool now_solid;
        if (y < c.reach_min) now_solid = !cave_here || cave_solid(&c, l, t, y);   /* the ground's part is surely positive */
        else now_solid = ground_density(&c, l, t, y) > 0.0f && (!cave_here || cave_solid(&c, l, t, y));
        if (now_solid != solid) {
            /* Place the crossing from the full density at both samples. */
            float d0 = density_exact(&c, previous_y), d1 = density_exact(&c, y);
            float crossing = (d0 > 0.0f) != (d1 > 0.0f) ? previous_y + d0 / (d0 - d1) * (y - previous_y)
                                                        : 0.5f * (previous_y + y);
            if (out->count < MAX_TRANSITIONS - 1) out->transitions[out->count++] = crossing;
            solid = now_solid;
        }
        previous_y = y;
    }
    /* Close a solid run left open (by y_hi or by a full buffer; one slot is kept for this). */
    if (out->count % 2 == 0) out->transitions[out->count++] = y_hi;
}

/* ---- floating islands (header comment, "Islands") ------------------------------------------ */

static int island_root(int *parent, int r) {
    while (parent[r] != r) r = parent[r] = parent[parent[r]];
    return r;
}

static void island_join(int *parent, int a, int b) {
    a = island_root(parent, a), b = island_root(parent, b);
    if (a != b) parent[CORE_MAX(a, b)] = CORE_MIN(a, b);
}

/* The chunk's solid runs for the island pass: run r spans quanta [lo[r], hi[r]) as the stacks
 * builder rounds them; a column's runs are first[c] … first[c + 1] − 1, bottom-up. */
typedef struct island_runs {
    int first[TERRAIN__COLUMNS + 1];
    int32_t *lo, *hi;
    int *parent;
    int count;
} island_runs;

/* Joins the runs of face-adjacent columns c0, c1 whose voxels share a face: y ranges that
 * overlap once rounded as the builder rounds them. Two quanta, not one: the builder rounds sums of
 * thicknesses, which may land a quantum off ours; a contact that thin counts as none, so the
 * removal errs towards air (what it keeps is held by firm contacts). */
static void island_join_columns(island_runs *runs, int c0, int c1) {
    int a = runs->first[c0], a_end = runs->first[c0 + 1], b = runs->first[c1], b_end = runs->first[c1 + 1];
    while (a < a_end && b < b_end) {
        int32_t lo = CORE_MAX(runs->lo[a], runs->lo[b]), hi = CORE_MIN(runs->hi[a], runs->hi[b]);
        if (hi - lo >= 2) island_join(runs->parent, a, b);
        if (runs->hi[a] < runs->hi[b]) a++;
        else b++;
    }
}

/* Removes the chunk's floating islands: solid runs that no chain of shared faces inside the chunk
 * links to the floor or to the chunk's outermost columns (beyond which the chunk sees nothing, so
 * what touches them is kept). What is removed touches no other chunk's column, so every chunk
 * decides alike; an island across a chunk border stays (header comment, "Islands"). Rewrites the
 * columns' transitions in place, from pool[start[c]], counts start[c + 1] − start[c]. Returns
 * the number of runs removed. */
static int islands_remove(float *pool, int *start) {
    island_runs runs;
    runs.count = 0;
    for (int c = 0; c < TERRAIN__COLUMNS; c++)
        runs.first[c] = runs.count, runs.count += (start[c + 1] - start[c] + 1) / 2;
    runs.first[TERRAIN__COLUMNS] = runs.count;
    if (runs.count == TERRAIN__COLUMNS) return 0;      /* a height field: every run is on the floor */
    size_t bytes = (size_t)runs.count * sizeof(int32_t), parent_bytes = (size_t)(runs.count + 1) * sizeof(int);
    runs.lo = core_alloc(bytes), runs.hi = core_alloc(bytes), runs.parent = core_alloc(parent_bytes);
    for (int c = 0; c < TERRAIN__COLUMNS; c++) {
        const float *t = pool + start[c];
        for (int r = 0, n = runs.first[c]; n < runs.first[c + 1]; r++, n++) {
            runs.lo[n] = (int32_t)llroundf((r == 0 ? TERRAIN_FLOOR_Y : t[2 * r - 1]) * TERRAIN__QUANTA_PER_METRE);
            runs.hi[n] = (int32_t)llroundf(t[2 * r] * TERRAIN__QUANTA_PER_METRE);
        }
    }
    int held = runs.count;                             /* the floor and the chunk's border */
    for (int r = 0; r <= runs.count; r++) runs.parent[r] = r;
    for (int k = 0; k < TERRAIN_CHUNK_COLUMNS; k++) {
        for (int i = 0; i < TERRAIN_CHUNK_COLUMNS; i++) {
            int c = k * TERRAIN_CHUNK_COLUMNS + i;
            bool border = i == 0 || k == 0 || i == TERRAIN_CHUNK_COLUMNS - 1 || k == TERRAIN_CHUNK_COLUMNS - 1;
            for (int r = runs.first[c]; r < runs.first[c + 1]; r++)
                if (border || r == runs.first[c]) island_join(runs.parent, r, held);
            if (i + 1 < TERRAIN_CHUNK_COLUMNS) island_join_columns(&runs, c, c + 1);
            if (k + 1 < TERRAIN_CHUNK_COLUMNS) island_join_columns(&runs, c, c + TERRAIN_CHUNK_COLUMNS);
        }
    }
    int removed = 0, write = 0, held_root = island_root(runs.parent, held);
    for (int c = 0; c < TERRAIN__COLUMNS; c++) {
        const float *t = pool + start[c];
        int count = start[c + 1] - start[c], begin = write;
        for (int r = 0; 2 * r < count; r++) {
            if (island_root(runs.parent, runs.first[c] + r) != held_root) {
                removed++;
                continue;                              /* its bottom and top go: air joins air */
            }
            float bottom = r == 0 ? 0.0f : t[2 * r - 1], top = t[2 * r];   /* read before written */
            if (r > 0) pool[write++] = bottom;
            pool[write++] = top;
        }
        start[c] = begin;
    }
    start[TERRAIN__COLUMNS] = write;
    core_free(runs.lo, bytes);
    core_free(runs.hi, bytes);
    core_free(runs.parent, parent_bytes);
    return removed;
}

/* ---- rock layers (header comment, "Rocks") ---------------------------------------------- */

/* Where a ring column's top is looked for: the column's own sample positions (column_range's)
 * from just below its ground's reach to just above it. */
static void ring_scan(const chunk_gen *g, int i, int k, float *y_lo, int *j_lo, int *j_hi) {
    float lo, hi;
    column_range(g, i, k, &lo, &hi);
    *y_lo = lo;
    *j_lo = CORE_MAX((int)floorf((g->reach_min[reach_index(i, k)] - SAMPLE_STEP - lo) / SAMPLE_STEP), 0);
    *j_hi = (int)ceilf((hi - lo) / SAMPLE_STEP);
}

static float ring_density(const column_context *c, int l0, int l1, float y) {
    float level = clampf((y - c->g->y_base) * (1.0f / COARSE_Y), (float)l0, (float)l1 - 1e-3f);
    int l = (int)level;
    return ground_density(c, l, level - (float)l, y);
}

/* The top of a ring column (outside the chunk): the ground's crossing, at column_generate's
 * sample positions but without caves, from the lattice's ring nodes, looked for from the
 * column's own G: up while solid, else down. An estimate of what the neighbouring chunk makes
 * there (it misses an overhang's lip above open air), close enough to see walls by. */
static float ring_top(const chunk_gen *g, int i, int k, float *fields) {
    float y_lo;
    int j_lo, j_hi;
    ring_scan(g, i, k, &y_lo, &j_lo, &j_hi);
    int octaves = g->model.perturbation_octaves;
    int l0 = clamp_int((int)((y_lo + (float)j_lo * SAMPLE_STEP - g->y_base) / COARSE_Y), g->ring_level_lo,
                       g->ring_level_hi);
    int l1 = clamp_int((int)((y_lo + (float)j_hi * SAMPLE_STEP - g->y_base) / COARSE_Y) + 1, g->ring_level_lo,
                       g->ring_level_hi);
    column_fields(g, i, k, 2 * octaves, l0, l1, fields);
    column_context c = { .g = g, .gx = (float)(i + g->margin), .gz = (float)(k + g->margin), .octaves = octaves,
                         .levels = g->levels };
    c.u = fields;
    c.w = fields + (size_t)octaves * g->levels;
    float ground = g->heights[(k + g->margin) * g->ground_size + i + g->margin];
    int j = clamp_int((int)lroundf((ground - y_lo) / SAMPLE_STEP), j_lo, j_hi);
    float y = y_lo + (float)j * SAMPLE_STEP, d = ring_density(&c, l0, l1, y);
    if (d > 0.0f) {
        for (j++; j <= j_hi; j++) {
            float y1 = y_lo + (float)j * SAMPLE_STEP, d1 = ring_density(&c, l0, l1, y1);
            if (d1 <= 0.0f) return y + d / (d - d1) * SAMPLE_STEP;
            y = y1, d = d1;
        }
        return y;
    }
    for (j--; j >= j_lo; j--) {
        float y0 = y_lo + (float)j * SAMPLE_STEP, d0 = ring_density(&c, l0, l1, y0);
        if (d0 > 0.0f) return y0 + d0 / (d0 - d) * SAMPLE_STEP;
        y = y0, d = d0;
    }
    return y;
}

static float smoothstep(float lo, float hi, float v) {
    float t = clampf((v - lo) / (hi - lo), 0.0f, 1.0f);
    return t * t * (3.0f - 2.0f * t);
}

/* A rock depth parameter: 0 its default, < 0 none. */
static float rock_depth(float value, float fallback) {
    return value == 0.0f ? fallback : value > 0.0f && isfinite(value) ? CORE_MIN(value, 32.0f) : 0.0f;
}

static const int8_t rock_dir[8][2] = { { 1, 0 }, { -1, 0 }, { 0, 1 }, { 0, -1 }, { 1, 1 }, { -1, 1 }, { 1, -1 }, { -1, -1 } };
static const float rock_dist[8] = { 1, 1, 1, 1, 1.41421356f, 1.41421356f, 1.41421356f, 1.41421356f };

/* Rock thickness over the chunk and its ring ([reach_index]) from the tops there (top of the
 * highest solid run) and the lake levels (NAN outside a lake's water circle). */
static void rock_layers(const chunk_gen *g, const float *top, const float *lake, float *rock) {
    const terrain_generation_desc *p = g->params;
    float talus = rock_depth(p->talus_depth, TALUS_DEPTH), scree = rock_depth(p->scree_depth, SCREE_DEPTH);
    float lake_rocks = rock_depth(p->lake_rocks_depth, LAKE_ROCKS_DEPTH);
    float scree_slope = p->scree_min_slope > 0.0f ? p->scree_min_slope : SCREE_MIN_SLOPE;
    int n = ROCK_SIDE;
    float *surface = rock + (size_t)n * n;            /* talus surface, then patch noise */
    for (int c = 0; c < n * n; c++) rock[c] = 0.0f, surface[c] = -INFINITY;
    if (!(talus > 0.0f || scree > 0.0f || lake_rocks > 0.0f)) return;
    float cone_drop[2 * TALUS_REACH + 1][2 * TALUS_REACH + 1];
    for (int dz = -TALUS_REACH; dz <= TALUS_REACH; dz++)
        for (int dx = -TALUS_REACH; dx <= TALUS_REACH; dx++)
            cone_drop[dz + TALUS_REACH][dx + TALUS_REACH] = TALUS_SLOPE * sqrtf((float)(dx * dx + dz * dz));
    /* Feet of walls: a neighbour rises faster than FOOT_RISE, none falls faster than rocks hold
     * (the riser's own columns fall steeply on their other side). A cone of rocks leans on each,
     * its surface talus·(how steep the wall is) above the foot, falling at TALUS_SLOPE. */
    for (int k = 1; k + 1 < n; k++) {
        for (int i = 1; i + 1 < n; i++) {
            int at = k * n + i;
            float rise = 0.0f, fall = 0.0f;
            for (int d = 0; d < 8; d++) {
                float step = (top[at + rock_dir[d][1] * n + rock_dir[d][0]] - top[at]) * (d < 4 ? 1.0f : 0.70710678f);
                rise = CORE_MAX(rise, step);
                fall = CORE_MAX(fall, -step);
            }
            float foot = talus * smoothstep(FOOT_RISE, 2.0f * FOOT_RISE, rise);
            if (fall <= ROCK_HOLD_SLOPE && foot > ROCK_MIN && top[at] > p->sea_level) {
                for (int dz = -TALUS_REACH; dz <= TALUS_REACH; dz++) {
                    for (int dx = -TALUS_REACH; dx <= TALUS_REACH; dx++) {
                        int x = i + dx, z = k + dz;
                        if (x < 0 || z < 0 || x >= n || z >= n) continue;
                        float cone = top[at] + foot - cone_drop[dz + TALUS_REACH][dx + TALUS_REACH];
                        surface[z * n + x] = CORE_MAX(surface[z * n + x], cone);
                    }
                }
            }
            /* Scree: where the ground falls faster than sand holds. */
            rock[at] = fall > scree_slope && fall < 1.0f && top[at] > p->sea_level
                           ? scree * smoothstep(scree_slope, scree_slope + 0.08f, fall) : 0.0f;
        }
    }
    for (int c = 0; c < n * n; c++) surface[c] = clampf(surface[c] - top[c], 0.0f, 1.2f * talus);
    /* Scree in patches, stones in a noisy ring at a lake's waterline. */
    uint32_t scree_seed = field_seed(p, 5), lake_seed = field_seed(p, 6);
    float xs[ROCK_SIDE], scree_noise[ROCK_SIDE], lake_noise[ROCK_SIDE];
    /* Offsets from the chunk's corner, which the noise splits in double (terrain__lattice_split). */
    double x0 = g->x0 * (1.0 / SCREE_WAVELENGTH);
    for (int i = 0; i < n; i++) xs[i] = (float)(((double)(i - ROCK_RING) + 0.5) * (1.0 / SCREE_WAVELENGTH));
    for (int k = 0; k < n; k++) {
        double z = (g->z0 + (double)(k - ROCK_RING) + 0.5) * (1.0 / SCREE_WAVELENGTH);
        bool stony = false, lakeside = false;            /* the noise only where it is read */
        for (int i = 0; i < n; i++) {
            stony |= rock[k * n + i] > 0.0f || surface[k * n + i] > 0.0f;
            lakeside |= !isnan(lake[k * n + i]);
        }
        if (!stony && !(lakeside && lake_rocks > 0.0f)) continue;
        terrain__noise2_row(scree_seed, x0, xs, 1.0f, z, n, scree_noise);
        if (lakeside) terrain__noise2_row(lake_seed, 2.0 * x0, xs, 2.0f, 2.0 * z, n, lake_noise);
        for (int i = 0; i < n; i++) {
            int at = k * n + i;
            float r = rock[at] * smoothstep(0.0f, 0.3f, scree_noise[i]);
            r = CORE_MAX(r, surface[at] * (0.8f + 0.2f * scree_noise[i]));
            if (lake_rocks > 0.0f && !isnan(lake[at])) {
                float h = top[at] - lake[at];
                float band = smoothstep(-2.0f, -1.2f, h) * (1.0f - smoothstep(0.8f, 1.6f, h));
                r = CORE_MAX(r, lake_rocks * band * smoothstep(-0.1f, 0.25f, lake_noise[i]));
            }
            rock[at] = r >= ROCK_MIN ? floorf(r / TERRAIN_HEIGHT_QUANTUM) * TERRAIN_HEIGHT_QUANTUM : 0.0f;
        }
    }
    /* Never steeper than rocks hold: a column's rock surface stays within d·ROCK_HOLD_SLOPE of
     * every neighbour's ground, thinned (never thickened) until that holds, in a fixed order. */
    int stony[(ROCK_SIDE - 2) * (ROCK_SIDE - 2)], count = 0;
    for (int k = 1; k + 1 < n; k++)
        for (int i = 1; i + 1 < n; i++)
            if (rock[k * n + i] > 0.0f) stony[count++] = k * n + i;
    for (int pass = 0; pass < ROCK_CLIP_PASSES && count; pass++) {
        bool changed = false;
        for (int c = 0; c < count; c++) {
            int at = stony[c];
            if (rock[at] <= 0.0f) continue;
            float limit = INFINITY;
            for (int d = 0; d < 8; d++) {
                int nb = at + rock_dir[d][1] * n + rock_dir[d][0];
                limit = CORE_MIN(limit, top[nb] + rock[nb] + ROCK_HOLD_SLOPE * rock_dist[d]);
            }
            float allowed = limit - top[at];
            if (rock[at] <= allowed) continue;
            float r = floorf(allowed / TERRAIN_HEIGHT_QUANTUM) * TERRAIN_HEIGHT_QUANTUM;
            rock[at] = r >= ROCK_MIN ? r : 0.0f;
            changed = true;
        }
        if (!changed) break;
    }
}

/* Pushes a column: bedrock/air runs, then sand and rocks on the top run and water above it. */
static void column_push(const chunk_gen *g, int i, int k, const float *transitions, int count, float rocks,
                        terrain_stacks_builder *builder) {
    const terrain_generation_desc *p = g->params;
    float top = transitions[count - 1];
    float top_run_bottom = count >= 3 ? transitions[count - 2] : TERRAIN_FLOOR_Y;
    /* Sand on low slopes: the macro ground's gradient at the column, central differences. */
    int size = g->ground_size, at = (k + g->margin) * size + i + g->margin;
    float slope_x = 0.5f * (g->heights[at + 1] - g->heights[at - 1]);
    float slope_z = 0.5f * (g->heights[at + size] - g->heights[at - size]);
    float slope = sqrtf(slope_x * slope_x + slope_z * slope_z);
    float sand = 0.0f;
    if (p->sand_max_slope > 0.0f && p->sand_depth > 0.0f)
        sand = p->sand_depth * clampf(1.0f - slope / p->sand_max_slope, 0.0f, 1.0f);
    /* A lake's basin is a beach: its full sand depth whatever the shore's slope. Thinner sand over
     * the basin's regular rings of slope let the bedrock under it into the visible-share weights
     * (000 §6) by amounts that beat with the mesh's cell size: concentric bands on every shore. */
    sand = fmaxf(sand, g->basin[k * TERRAIN_CHUNK_COLUMNS + i] * p->sand_depth);
    sand = CORE_MIN(sand, top - top_run_bottom);

    float y = TERRAIN_FLOOR_Y;
    for (int t = 0; t < count; t++) {
        float next = transitions[t];
        if (t % 2) {
            terrain_stacks_builder_push(builder, TERRAIN_AIR, next - y);
        } else if (t == count - 1) {      /* the highest solid run: sand, then rocks (000 §3.4) */
            terrain_stacks_builder_push(builder, TERRAIN_BEDROCK, next - sand - y);
            terrain_stacks_builder_push(builder, TERRAIN_SAND, sand);
            terrain_stacks_builder_push(builder, TERRAIN_ROCKS, rocks);
        } else {
            terrain_stacks_builder_push(builder, TERRAIN_BEDROCK, next - y);
        }
        y = next;
    }
    float lake = g->lake_levels[k * TERRAIN_CHUNK_COLUMNS + i];
    top += rocks;
    if (top < p->sea_level) terrain_stacks_builder_push(builder, TERRAIN_WATER, p->sea_level - top);
    else if (top < lake) terrain_stacks_builder_push(builder, TERRAIN_WATER, lake - top);   /* NAN: never */
    terrain_stacks_builder_end_column(builder);
}

terrain_stacks *terrain_generate_chunk(const terrain_generation_desc *params, terrain_chunk_coord coord) {
    chunk_gen g = { .params = params };
    g.model = ground_model_make(params);
    g.model.lakes = &g.lakes;                      /* the chunk's grid rows share the sites */
    g.x0 = (double)coord.x * TERRAIN_CHUNK_COLUMNS * TERRAIN_COLUMN_SIZE;
    g.z0 = (double)coord.z * TERRAIN_CHUNK_COLUMNS * TERRAIN_COLUMN_SIZE;
    /* |u|, |w| ≤ 1 (normalised fBm of clamped noise), so a displaced point stays within A. */
    g.displacement = clampf(params->horizontal_perturbation, 0.0f, 64.0f);
    int reach = (int)ceilf(g.displacement) + 1;    /* + 1: bilinear reads the next column */
    g.margin = CORE_MAX(reach + 1, ROCK_RING);     /* + 1: slopes by central differences; the rock
                                                      ring reads G at its own columns */
    g.ground_size = TERRAIN_CHUNK_COLUMNS + 2 * g.margin;
    size_t grid_bytes = (size_t)g.ground_size * g.ground_size * sizeof(float);
    size_t column_bytes = (size_t)TERRAIN__COLUMNS * sizeof(float);
    size_t ring_bytes = (size_t)ROCK_SIDE * ROCK_SIDE * sizeof(float);
    g.heights = core_alloc(grid_bytes);
    g.reach_min = core_alloc(ring_bytes);
    g.reach_max = core_alloc(ring_bytes);
    ground_grid(&g);
    ground_reach(&g, reach);
    g.lake_levels = core_alloc(column_bytes);
    g.basin = core_alloc(column_bytes);
    for (int k = 0; k < TERRAIN_CHUNK_COLUMNS; k++)
        for (int i = 0; i < TERRAIN_CHUNK_COLUMNS; i++)
            g.lake_levels[k * TERRAIN_CHUNK_COLUMNS + i] = lake_level_at(&g.model, g.x0 + i + 0.5, g.z0 + k + 0.5,
                                                                           &g.basin[k * TERRAIN_CHUNK_COLUMNS + i]);

    /* The chunk's y range, then the coarse lattice over it. */
    float y_lo = INFINITY, y_hi = -INFINITY;
    for (int k = 0; k < TERRAIN_CHUNK_COLUMNS; k++) {
        for (int i = 0; i < TERRAIN_CHUNK_COLUMNS; i++) {
            float lo, hi;
            column_range(&g, i, k, &lo, &hi);
            y_lo = CORE_MIN(y_lo, lo);
            y_hi = CORE_MAX(y_hi, hi);
        }
    }
    /* And where the rock ring's tops mostly are: around its own G (ring_top reads the nearest
     * level beyond these, and nothing above the chunk's own range: an estimate). */
    float ring_lo = INFINITY, ring_hi = -INFINITY;
    for (int k = -ROCK_RING; k < TERRAIN_CHUNK_COLUMNS + ROCK_RING; k++) {
        for (int i = -ROCK_RING; i < TERRAIN_CHUNK_COLUMNS + ROCK_RING; i++) {
            float ground = g.heights[(k + g.margin) * g.ground_size + i + g.margin];
            ring_lo = CORE_MIN(ring_lo, ground - RING_LEVELS_AROUND);
            ring_hi = CORE_MAX(ring_hi, ground + RING_LEVELS_AROUND);
        }
    }
    coarse_setup(&g);
    /* + 2 steps: the last sample may pass y_hi. */
    coarse_lattice(&g, y_lo, y_hi + 2.0f * SAMPLE_STEP, ring_lo, ring_hi);

    size_t fields_bytes = (size_t)g.fields * g.levels * sizeof(float);
    float *fields = core_alloc(fields_bytes ? fields_bytes : sizeof(float));
    column_layers *layers = core_alloc(sizeof *layers);
    bool *cave_possible = core_calloc((size_t)g.levels, sizeof(bool));
    /* Every column's transitions first: the rocks need the tops around each column. */
    size_t pool_capacity = (size_t)TERRAIN__COLUMNS * 8, pool_used = 0;
    float *pool = core_alloc(pool_capacity * sizeof(float));
    int *pool_start = core_alloc((TERRAIN__COLUMNS + 1) * sizeof(int));
    float *tops = core_alloc(2 * ring_bytes), *lakes = tops + ROCK_SIDE * ROCK_SIDE;
    float *rocks = core_alloc(2 * ring_bytes);
    for (int k = 0; k < TERRAIN_CHUNK_COLUMNS; k++) {
        for (int i = 0; i < TERRAIN_CHUNK_COLUMNS; i++) {
            column_fields(&g, i, k, g.fields, 0, g.levels - 1, fields);
            column_generate(&g, i, k, fields, cave_possible, layers);
            if (pool_used + (size_t)layers->count > pool_capacity) {
                size_t grown = CORE_MAX(2 * pool_capacity, pool_used + (size_t)layers->count);
                pool = core_realloc(pool, pool_capacity * sizeof(float), grown * sizeof(float));
                pool_capacity = grown;
            }
            memcpy(pool + pool_used, layers->transitions, (size_t)layers->count * sizeof(float));
            pool_start[k * TERRAIN_CHUNK_COLUMNS + i] = (int)pool_used;
            pool_used += (size_t)layers->count;
        }
    }
    pool_start[TERRAIN__COLUMNS] = (int)pool_used;
    islands_remove(pool, pool_start);                /* before the tops: an island is no top */
    for (int k = 0; k < TERRAIN_CHUNK_COLUMNS; k++) {
        for (int i = 0; i < TERRAIN_CHUNK_COLUMNS; i++) {
            int c = k * TERRAIN_CHUNK_COLUMNS + i;
            tops[reach_index(i, k)] = pool[pool_start[c + 1] - 1];
            lakes[reach_index(i, k)] = g.lake_levels[c];
        }
    }
    for (int k = -ROCK_RING; k < TERRAIN_CHUNK_COLUMNS + ROCK_RING; k++) {
        for (int i = -ROCK_RING; i < TERRAIN_CHUNK_COLUMNS + ROCK_RING; i++) {
            if (i >= 0 && k >= 0 && i < TERRAIN_CHUNK_COLUMNS && k < TERRAIN_CHUNK_COLUMNS) continue;
            float basin;
            tops[reach_index(i, k)] = ring_top(&g, i, k, fields);
            lakes[reach_index(i, k)] = lake_level_at(&g.model, g.x0 + i + 0.5, g.z0 + k + 0.5, &basin);
        }
    }
    rock_layers(&g, tops, lakes, rocks);
    terrain_stacks_builder *builder = terrain_stacks_builder_create();
    for (int c = 0; c < TERRAIN__COLUMNS; c++) {
        int i = c % TERRAIN_CHUNK_COLUMNS, k = c / TERRAIN_CHUNK_COLUMNS;
        column_push(&g, i, k, pool + pool_start[c], pool_start[c + 1] - pool_start[c], rocks[reach_index(i, k)],
                    builder);
    }
    terrain_stacks *stacks = terrain_stacks_builder_finish(builder);
    terrain_stacks_builder_destroy(builder);
    core_free(pool, pool_capacity * sizeof(float));
    core_free(pool_start, (TERRAIN__COLUMNS + 1) * sizeof(int));
    core_free(tops, 2 * ring_bytes);
    core_free(rocks, 2 * ring_bytes);
    core_free(layers, sizeof *layers);
    core_free(cave_possible, (size_t)g.levels * sizeof(bool));
    core_free(fields, fields_bytes ? fields_bytes : sizeof(float));
    core_free(g.coarse, lattice_floats(&g) * sizeof(float));
    core_free(g.heights, grid_bytes);
    core_free(g.reach_min, ring_bytes);
    core_free(g.reach_max, ring_bytes);
    core_free(g.lake_levels, column_bytes);
    core_free(g.basin, column_bytes);
    return stacks;
}
