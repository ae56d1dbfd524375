/* rocks_tiles.c — the tile set's parameters, seeds and regions, and its assembly from the 318
 * region instances (001 §2–§3).
 *
 * Seeds (001 §3). The paper builds the seeds in order: the 2 vertex regions and their neighbour
 * cells, then the 12 edge regions copying what the vertices fixed and filling the rest, then the
 * 48 faces, then the 256 centres. We get the same result without any order: a cell's seeds are a
 * pure function of the lowest-dimensional lattice feature whose closure (the region with its
 * 1-neighbourhood) holds the cell, that feature's corner colours, the cell's offset from the
 * feature's origin and desc.seed. Per axis a cell with index 0 or 1 in its tile is in the closure
 * of the lattice plane below, n − 2 or n − 1 of the plane above, anything else of the tile's
 * interior; the planes an axis is "near" fix the feature (three: a vertex, two: an edge, one: a
 * face, none: the centre). For n ≥ 4 the two planes of a tile are never both near one cell, so
 * the feature is unique; copying "what the lower regions fixed" is then exactly this rule.
 */
#include "rocks_internal.h"

#include "core/core.h"
#include "jobs/jobs.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const float rocks_hull_axes[ROCKS_HULL_AXES][3] = {
    { 1, 0, 0 },  { 0, 1, 0 },  { 0, 0, 1 },                                  /* the axes */
    { 1, 1, 0 },  { 1, -1, 0 }, { 1, 0, 1 },  { 1, 0, -1 }, { 0, 1, 1 }, { 0, 1, -1 },   /* faces */
    { 1, 1, 1 },  { 1, 1, -1 }, { 1, -1, 1 }, { 1, -1, -1 },                  /* body diagonals */
};

/* ---- parameters ----------------------------------------------------------------------------- */

static bool bad(const char *what, double value) {
    core_log_error("rocks", "tile set: %s is out of range (%g)", what, value);
    return false;
}

bool rocks__params_make(const rocks_tileset_desc *desc_in, rocks__params *out) {
    rocks_tileset_desc d = *desc_in;
    d.jobs = NULL;
    d.cache_path = NULL;
    if (d.seed == 0) d.seed = 1;
    if (d.cells == 0) d.cells = 5;
    if (d.cells < 4 || d.cells > 8) return bad("cells (4 … 8)", d.cells);
    if (d.voxels_per_cell == 0) d.voxels_per_cell = 10;
    if (d.voxels_per_cell < 4 || d.voxels_per_cell > 16) return bad("voxels_per_cell (4 … 16)", d.voxels_per_cell);
    if (d.shape == ROCKS_SHAPE_DEFAULT) d.shape = ROCKS_SHAPE_MIXED;
    if (d.shape != ROCKS_SHAPE_ROUND && d.shape != ROCKS_SHAPE_SLAB && d.shape != ROCKS_SHAPE_MIXED)
        return bad("shape", d.shape);
    float smin[3], smax[3], g_max;
    int s;
    switch (d.shape) {
    case ROCKS_SHAPE_ROUND:   /* 001 Fig. 11 */
        for (int a = 0; a < 3; a++) smin[a] = smax[a] = 1.0f;
        g_max = 2.0f, s = 1;
        break;
    case ROCKS_SHAPE_SLAB:    /* 001 Fig. 13 */
        smin[0] = smin[1] = 4.0f, smax[0] = smax[1] = 5.0f, smin[2] = smax[2] = 1.0f;
        g_max = 3.0f, s = 1;
        break;
    default:                  /* 001 Fig. 12, with a narrower range of seed counts */
        for (int a = 0; a < 3; a++) smin[a] = 1.0f, smax[a] = 2.0f;
        g_max = 4.0f, s = 3;
        break;
    }
    for (int a = 0; a < 3; a++) {
        if (d.scale_min[a] == 0.0f && d.scale_max[a] == 0.0f) d.scale_min[a] = smin[a], d.scale_max[a] = smax[a];
        if (!(d.scale_min[a] > 0.0f) || !(d.scale_max[a] >= d.scale_min[a]) || d.scale_max[a] > 100.0f)
            return bad("scale range", d.scale_min[a]);
    }
    if (d.g_max == 0.0f) d.g_max = g_max;
    if (!(d.g_max >= 1.0f && d.g_max <= 16.0f)) return bad("g_max (1 … 16)", d.g_max);
    bool fixed = d.shape != ROCKS_SHAPE_MIXED;
    if (d.max_seeds_per_cell == 0) d.max_seeds_per_cell = s;
    if (d.max_seeds_per_cell < 1 || d.max_seeds_per_cell > ROCKS__MAX_SEEDS_PER_CELL)
        return bad("max_seeds_per_cell (1 … 8)", d.max_seeds_per_cell);
    if (d.contact_radius == 0.0f) d.contact_radius = 0.12f;
    if (d.blend_radius == 0.0f) d.blend_radius = 0.35f;
    if (!(d.contact_radius > 0.0f && d.contact_radius < 1.0f)) return bad("contact_radius", d.contact_radius);
    if (!(d.blend_radius > d.contact_radius && d.blend_radius <= 2.0f)) return bad("blend_radius (> contact_radius)", d.blend_radius);
    if (d.erosion_steps == 0) d.erosion_steps = 6;
    if (d.erosion_steps < 0 || d.erosion_steps > 64) return bad("erosion_steps (1 … 64)", d.erosion_steps);
    if (d.erosion_rate == 0.0f) d.erosion_rate = 0.25f;
    if (!(d.erosion_rate > 0.0f && d.erosion_rate <= 1.0f)) return bad("erosion_rate (0 … 1]", d.erosion_rate);

    memset(out, 0, sizeof *out);
    out->desc = d;
    out->n = d.cells;
    out->m = d.voxels_per_cell;
    out->seeds_max = d.max_seeds_per_cell;
    out->seeds_fixed = fixed;
    /* The contact radius is at least 1.7 voxels: a kept contact lies in a voxel of one rock
     * next to a voxel of the other (rocks_voronoi.c), both within 1.66 voxels of c_ij, so neither
     * erodes there (ω = 0) and both rocks keep a solid voxel at each of their contacts: no rock
     * with a contact is dropped, and both meshes pass by c_ij (001 §5's "no erosion within a"). */
    out->contact_voxels = fmaxf(d.contact_radius * (float)out->m, 1.7f);
    out->blend_voxels = fmaxf(d.blend_radius * (float)out->m, out->contact_voxels + 1.0f);
    return true;
}

/* ---- seeds (001 §3–§4) ------------------------------------------------------------------------ */

static double unit(uint64_t h) { return (double)(h >> 11) * (1.0 / 9007199254740992.0); }

int rocks__cell_seeds(const rocks__params *params, const int cell[3], rocks__colour_fn colour,
                      const void *user, rocks__seed *out) {
    const int n = params->n, m = params->m;
    int origin[3], offset[3], extended = 0;
    for (int a = 0; a < 3; a++) {
        int tile = rocks__floor_div(cell[a], n), i = cell[a] - tile * n;
        if (i <= 1) origin[a] = tile, offset[a] = i;                   /* near the plane below */
        else if (i >= n - 2) origin[a] = tile + 1, offset[a] = i - n;  /* near the plane above */
        else origin[a] = tile, offset[a] = i, extended |= 1 << a;      /* the tile's interior */
    }
    /* The feature's corners: origin + any subset of its extended axes, in bit order. */
    uint64_t colours = 0;
    int corner = 0;
    for (int bits = 0; bits < 8; bits++) {
        if (bits & ~extended) continue;
        int c = colour(user, origin[0] + (bits & 1), origin[1] + ((bits >> 1) & 1), origin[2] + ((bits >> 2) & 1));
        colours |= (uint64_t)(c & 1) << corner++;
    }
    uint64_t key = core_hash_combine(params->desc.seed, 0x726f636b73ull);   /* "rocks" */
    key = core_hash_combine(key, (uint64_t)extended);
    key = core_hash_combine(key, colours);
    for (int a = 0; a < 3; a++) key = core_hash_combine(key, (uint64_t)(offset[a] + 16));

    int count = params->seeds_fixed ? params->seeds_max
                                    : 1 + (int)(core_hash_combine(key, 1) % (uint64_t)params->seeds_max);
    /* A hashed start and the R3 sequence (Roberts' generalised golden ratio) after it: a low
     * discrepancy set of n_k points in the cell (001 §3). */
    static const double r3[3] = { 0.8191725133961645, 0.6710436067037893, 0.5497004779019703 };
    double start[3] = { unit(core_hash_combine(key, 2)), unit(core_hash_combine(key, 3)),
                        unit(core_hash_combine(key, 4)) };
    const rocks_tileset_desc *d = &params->desc;
    for (int j = 0; j < count; j++) {
        rocks__seed *s = &out[j];
        uint64_t h = core_hash_combine(key, 100 + (uint64_t)j);
        s->id = h;
        s->k = j;
        for (int a = 0; a < 3; a++) {
            s->cell[a] = cell[a];
            double u = start[a] + r3[a] * j;
            u -= floor(u);
            float um = (float)(u * m);
            s->u[a] = fminf(um, (float)m - 1e-3f);
        }
        /* A uniform random frame (Shoemake's quaternion), α, β, γ and g_k (001 §4). */
        double u1 = unit(core_hash_combine(h, 1)), u2 = unit(core_hash_combine(h, 2)), u3 = unit(core_hash_combine(h, 3));
        double qx = sqrt(1 - u1) * sin(2 * M_PI * u2), qy = sqrt(1 - u1) * cos(2 * M_PI * u2);
        double qz = sqrt(u1) * sin(2 * M_PI * u3), qw = sqrt(u1) * cos(2 * M_PI * u3);
        double rot[3][3] = {   /* columns are the frame's x, y, z */
            { 1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw) },
            { 2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw) },
            { 2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy) },
        };
        double scale[3];
        for (int a = 0; a < 3; a++)
            scale[a] = d->scale_min[a] + (d->scale_max[a] - d->scale_min[a]) * unit(core_hash_combine(h, 4 + (uint64_t)a));
        double g = 1.0 + (d->g_max - 1.0) * unit(core_hash_combine(h, 7));
        double q[3][3] = { { 0 } };
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 3; c++)
                for (int a = 0; a < 3; a++) q[r][c] += scale[a] * rot[r][a] * rot[c][a] / g;
        s->q[0] = (float)q[0][0], s->q[1] = (float)q[1][1], s->q[2] = (float)q[2][2];
        s->q[3] = (float)(2 * q[0][1]), s->q[4] = (float)(2 * q[0][2]), s->q[5] = (float)(2 * q[1][2]);
        s->q_min = (float)(fmin(scale[0], fmin(scale[1], scale[2])) / g);
    }
    return count;
}

/* ---- regions ---------------------------------------------------------------------------------- */

void rocks__region_make(const rocks__params *params, int index, rocks__region *out) {
    const int n = params->n;
    memset(out, 0, sizeof *out);
    int fixed_lo = -1, fixed_hi = 0, ext_lo = 1, ext_hi = n - 2;
    int extended = 0;
    if (index < 2) {
        out->kind = ROCKS__VERTEX;
        out->colour[0][0][0] = (uint8_t)index, out->known[0][0][0] = true;
    } else if (index < 14) {
        int e = index - 2, axis = e / 4, bits = e % 4;
        out->kind = ROCKS__EDGE, out->axis = axis, extended = 1 << axis;
        int p1[3] = { 0, 0, 0 };
        p1[axis] = 1;
        out->colour[0][0][0] = bits & 1, out->known[0][0][0] = true;
        out->colour[p1[2]][p1[1]][p1[0]] = (bits >> 1) & 1, out->known[p1[2]][p1[1]][p1[0]] = true;
    } else if (index < 62) {
        int f = index - 14, axis = f / 16, bits = f % 16;
        int b = axis == 0 ? 1 : 0, c = axis == 2 ? 1 : 2;
        out->kind = ROCKS__FACE, out->axis = axis, extended = (1 << b) | (1 << c);
        for (int j = 0; j < 2; j++)
            for (int i = 0; i < 2; i++) {
                int p[3] = { 0, 0, 0 };
                p[b] = i, p[c] = j;
                out->colour[p[2]][p[1]][p[0]] = (bits >> (i + 2 * j)) & 1;
                out->known[p[2]][p[1]][p[0]] = true;
            }
    } else {
        int t = index - 62;
        out->kind = ROCKS__CENTRE, extended = 7;
        for (int z = 0; z < 2; z++)
            for (int y = 0; y < 2; y++)
                for (int x = 0; x < 2; x++)
                    out->colour[z][y][x] = (t >> (x + 2 * y + 4 * z)) & 1, out->known[z][y][x] = true;
    }
    for (int a = 0; a < 3; a++) {
        bool ext = extended & (1 << a);
        out->lo[a] = ext ? ext_lo : fixed_lo;
        out->hi[a] = ext ? ext_hi : fixed_hi;
    }
}

int rocks__region_of_cell(const rocks__params *params, const int cell[3], const bool known[2][2][2],
                          const uint8_t colour[2][2][2], int origin[3]) {
    const int n = params->n;
    int extended = 0, count = 0;
    for (int a = 0; a < 3; a++) {
        int tile = rocks__floor_div(cell[a], n), i = cell[a] - tile * n;
        if (i == 0) origin[a] = tile;
        else if (i == n - 1) origin[a] = tile + 1;
        else origin[a] = tile, extended |= 1 << a, count++;
    }
    int bits = 0, corner = 0;
    for (int b = 0; b < 8; b++) {
        if (b & ~extended) continue;
        int p[3] = { origin[0] + (b & 1), origin[1] + ((b >> 1) & 1), origin[2] + ((b >> 2) & 1) };
        for (int a = 0; a < 3; a++)
            if (p[a] < 0 || p[a] > 1) return -1;
        if (!known[p[2]][p[1]][p[0]]) return -1;
        bits |= (colour[p[2]][p[1]][p[0]] & 1) << corner++;
    }
    switch (count) {
    case 0: return bits;
    case 1: {
        int axis = extended == 1 ? 0 : extended == 2 ? 1 : 2;
        return 2 + axis * 4 + bits;
    }
    case 2: {
        int axis = extended == 6 ? 0 : extended == 5 ? 1 : 2;   /* the normal: the fixed axis */
        return 14 + axis * 16 + bits;
    }
    default: return 62 + bits;
    }
}

/* ---- building and assembling ------------------------------------------------------------------ */

typedef struct build_job {
    const rocks__params *params;
    const rocks__build_options *options;
    rocks__region_result *results;
} build_job;

static void build_range(void *user, size_t begin, size_t end) {
    build_job *job = user;
    for (size_t i = begin; i < end; i++) rocks__region_build(job->params, job->options, (int)i, &job->results[i]);
}

/* Rock index of (cell, k) in instance `region`: a linear scan of that instance's rocks (a few
 * hundred at most), run once per contact at assembly. */
static int64_t find_rock(const rocks__region_result *r, const uint32_t *rock_base, int region, const int cell[3], int k) {
    const rocks__region_result *res = &r[region];
    for (uint32_t i = 0; i < res->rock_count; i++)
        if (res->rock_k[i] == k && res->rock_cell[i][0] == cell[0] && res->rock_cell[i][1] == cell[1] &&
            res->rock_cell[i][2] == cell[2])
            return (int64_t)rock_base[region] + i;
    return -1;
}

static void assemble(rocks__set *full, rocks__region_result *results, bool keep_voxels) {
    rocks_tileset *set = &full->set;
    const rocks__params *params = &full->params;
    uint32_t rock_base[ROCKS__REGION_COUNT];
    size_t rocks = 0, vertices = 0, indices = 0, anchors = 0, contacts = 0, voxels = 0;
    for (int i = 0; i < ROCKS__REGION_COUNT; i++) {
        rock_base[i] = (uint32_t)rocks;
        rocks += results[i].rock_count, vertices += results[i].vertex_count;
        indices += results[i].index_count, anchors += results[i].anchor_count;
        contacts += results[i].contact_count, voxels += results[i].voxel_total;
    }
    set->rocks = core_calloc(rocks ? rocks : 1, sizeof *set->rocks);
    set->vertices = core_calloc(vertices ? vertices : 1, sizeof *set->vertices);
    set->indices = core_calloc(indices ? indices : 1, sizeof *set->indices);
    set->anchors = core_calloc(anchors ? anchors : 1, sizeof *set->anchors);
    set->contacts = core_calloc(contacts ? contacts : 1, sizeof *set->contacts);
    full->rock_region = core_calloc(rocks ? rocks : 1, sizeof *full->rock_region);
    full->rock_cell = core_calloc(rocks ? rocks : 1, sizeof *full->rock_cell);
    full->rock_k = core_calloc(rocks ? rocks : 1, sizeof *full->rock_k);
    if (keep_voxels) {
        full->voxels = core_calloc(voxels ? voxels : 1, sizeof *full->voxels);
        full->voxel_rho = core_calloc(voxels ? voxels : 1, sizeof *full->voxel_rho);
        full->voxel_first = core_calloc(rocks ? rocks : 1, sizeof *full->voxel_first);
        full->voxel_count = core_calloc(rocks ? rocks : 1, sizeof *full->voxel_count);
        full->voxel_total = (uint32_t)voxels;
    }
    uint32_t rv = 0, ri = 0, ra = 0, rc = 0, rx = 0, r = 0;
    float max_radius = 0.0f;
    for (int g = 0; g < ROCKS__REGION_COUNT; g++) {
        rocks__region_result *res = &results[g];
        memcpy(set->vertices + rv, res->vertices, res->vertex_count * sizeof *res->vertices);
        memcpy(set->indices + ri, res->indices, res->index_count * sizeof *res->indices);
        memcpy(set->anchors + ra, res->anchors, res->anchor_count * sizeof *res->anchors);
        for (uint32_t i = 0; i < res->rock_count; i++, r++) {
            rocks_rock rock = res->rocks[i];
            rock.vertex_first += rv;
            for (int l = 0; l < ROCKS_LODS; l++) rock.index_first[l] += ri;
            rock.anchor_first += ra;
            uint32_t first = rc;
            for (uint32_t c = rock.contact_first; c < rock.contact_first + rock.contact_count; c++) {
                rocks_contact contact = res->contacts[c];
                const int *o = res->contact_other[c];
                if (o[0] >= 0) {
                    int64_t other = find_rock(results, rock_base, o[0], o + 1, o[4]);
                    if (other < 0) continue;   /* cannot happen (rocks_params_make's floor on a) */
                    contact.other = (uint32_t)other;
                } else {
                    contact.other = ROCKS_CONTACT_VARIES;
                }
                set->contacts[rc++] = contact;
            }
            rock.contact_first = first;
            rock.contact_count = rc - first;
            set->rocks[r] = rock;
            full->rock_region[r] = (uint16_t)g;
            for (int a = 0; a < 3; a++) full->rock_cell[r][a] = (int16_t)res->rock_cell[i][a];
            full->rock_k[r] = (uint8_t)res->rock_k[i];
            if (rock.radius > max_radius) max_radius = rock.radius;
            if (keep_voxels) {
                full->voxel_first[r] = rx + res->voxel_first[i];
                full->voxel_count[r] = res->voxel_count[i];
            }
        }
        if (keep_voxels) {
            memcpy(full->voxels + rx, res->voxels, res->voxel_total * sizeof *res->voxels);
            memcpy(full->voxel_rho + rx, res->voxel_rho, res->voxel_total * sizeof *res->voxel_rho);
            rx += res->voxel_total;
        }
        rv += res->vertex_count, ri += res->index_count, ra += res->anchor_count;
    }
    set->rock_count = (uint32_t)rocks, set->vertex_count = (uint32_t)vertices;
    set->index_count = (uint32_t)indices, set->anchor_count = (uint32_t)anchors;
    set->contact_count = rc;
    set->max_radius = max_radius;

    /* Tiles: each of the 27 region pieces a tile touches (8 corners, 12 edges, 6 faces, its
     * centre), and of each region's rocks those whose seed cell lies in the tile. */
    const int n = params->n;
    size_t capacity = 0, count = 0;
    rocks_tile_entry *entries = NULL;
    bool all_known[2][2][2];
    memset(all_known, 1, sizeof all_known);
    for (int t = 0; t < 256; t++) {
        uint8_t colour[2][2][2];
        for (int z = 0; z < 2; z++)
            for (int y = 0; y < 2; y++)
                for (int x = 0; x < 2; x++) colour[z][y][x] = (t >> (x + 2 * y + 4 * z)) & 1;
        set->tiles[t].first = (uint32_t)count;
        for (int piece = 0; piece < 27; piece++) {
            int choice[3] = { piece % 3, (piece / 3) % 3, piece / 9 };   /* 0 low, 1 inside, 2 high */
            int probe[3], origin[3];
            for (int a = 0; a < 3; a++) probe[a] = choice[a] == 0 ? 0 : choice[a] == 1 ? 1 : n - 1;
            int region = rocks__region_of_cell(params, probe, all_known, colour, origin);
            const rocks__region_result *res = &results[region];
            for (uint32_t i = 0; i < res->rock_count; i++) {
                bool inside = true;
                for (int a = 0; a < 3; a++) {
                    int c = origin[a] * n + res->rock_cell[i][a];
                    inside &= c >= 0 && c < n;
                }
                if (!inside) continue;
                entries = core_grow(entries, &capacity, count + 1, sizeof *entries);
                entries[count] = (rocks_tile_entry){ .rock = rock_base[region] + i,
                                                     .offset = { (int8_t)origin[0], (int8_t)origin[1], (int8_t)origin[2] } };
                count++;
            }
        }
        set->tiles[t].count = (uint32_t)count - set->tiles[t].first;
    }
    set->entries = core_calloc(count ? count : 1, sizeof *set->entries);
    memcpy(set->entries, entries, count * sizeof *entries);
    core_free(entries, capacity * sizeof *entries);
    set->entry_count = (uint32_t)count;
}

size_t rocks__set_bytes(const rocks_tileset *set) {
    return sizeof(rocks__set) + set->entry_count * sizeof *set->entries + set->rock_count * sizeof *set->rocks +
           set->vertex_count * sizeof *set->vertices + set->index_count * sizeof *set->indices +
           set->anchor_count * sizeof *set->anchors + set->contact_count * sizeof *set->contacts +
           set->rock_count * (sizeof(uint16_t) + 3 * sizeof(int16_t) + sizeof(uint8_t));
}

/* Arrays are allocated with at least one item (so a zero count still has a pointer to free). */
#define FREE_ARRAY(p, count) (core_free((p), ((count) ? (count) : 1) * sizeof *(p)), (p) = NULL)

void rocks__set_free_arrays(rocks__set *full) {
    rocks_tileset *set = &full->set;
    if (set->entries) FREE_ARRAY(set->entries, set->entry_count);
    if (set->rocks) FREE_ARRAY(set->rocks, set->rock_count);
    if (set->vertices) FREE_ARRAY(set->vertices, set->vertex_count);
    if (set->indices) FREE_ARRAY(set->indices, set->index_count);
    if (set->anchors) FREE_ARRAY(set->anchors, set->anchor_count);
    if (set->contacts) FREE_ARRAY(set->contacts, set->contact_count);
    if (full->rock_region) FREE_ARRAY(full->rock_region, set->rock_count);
    if (full->rock_cell) FREE_ARRAY(full->rock_cell, set->rock_count);
    if (full->rock_k) FREE_ARRAY(full->rock_k, set->rock_count);
    if (full->voxels) FREE_ARRAY(full->voxels, full->voxel_total);
    if (full->voxel_rho) FREE_ARRAY(full->voxel_rho, full->voxel_total);
    if (full->voxel_first) FREE_ARRAY(full->voxel_first, set->rock_count);
    if (full->voxel_count) FREE_ARRAY(full->voxel_count, set->rock_count);
}

rocks_tileset *rocks__tiles_create(const rocks_tileset_desc *desc, const rocks__build_options *options_in) {
    rocks__build_options options = options_in ? *options_in : (rocks__build_options){ 0 };
    rocks__params params;
    if (!desc || !rocks__params_make(desc, &params)) return NULL;
    rocks__set *full = core_calloc(1, sizeof *full);
    full->params = params;
    full->set.desc = params.desc;
    const char *why = NULL;
    bool testing = options.keep_voxels || options.keep_empty;
    if (desc->cache_path && !testing && rocks__cache_read(desc->cache_path, &params, full, &why)) {
        full->set.from_cache = true;
        full->set.bytes = rocks__set_bytes(&full->set);
        return &full->set;
    }
    uint64_t t0 = core_time_ns();
    rocks__region_result *results = core_calloc(ROCKS__REGION_COUNT, sizeof *results);
    build_job job = { .params = &params, .options = &options, .results = results };
    if (desc->jobs) job_parallel_for(desc->jobs, ROCKS__REGION_COUNT, 1, build_range, &job, "rocks_region");
    else build_range(&job, 0, ROCKS__REGION_COUNT);
    assemble(full, results, options.keep_voxels);
    for (int i = 0; i < ROCKS__REGION_COUNT; i++) rocks__region_result_free(&results[i]);
    core_free(results, ROCKS__REGION_COUNT * sizeof *results);
    full->set.build_seconds = (double)(core_time_ns() - t0) * 1e-9;
    full->set.bytes = rocks__set_bytes(&full->set);
    if (desc->cache_path && !testing) {
        bool written = rocks__cache_write(desc->cache_path, full);
        core_warn("rocks", "tile cache %s: %s; rebuilt in %.1f s%s", desc->cache_path, why ? why : "not read",
                  full->set.build_seconds, written ? " and rewrote it" : " (could not rewrite it)");
    }
    return &full->set;
}

rocks_tileset *rocks_tileset_create(const rocks_tileset_desc *desc) { return rocks__tiles_create(desc, NULL); }

void rocks_tiles_release_meshes(rocks_tileset *set) {
    if (!set || !set->vertices) return;
    size_t bytes = (size_t)set->vertex_count * sizeof *set->vertices + (size_t)set->index_count * sizeof *set->indices;
    FREE_ARRAY(set->vertices, set->vertex_count);
    FREE_ARRAY(set->indices, set->index_count);
    set->bytes = set->bytes > bytes ? set->bytes - bytes : 0;
}

void rocks_tileset_destroy(rocks_tileset *set) {
    if (!set) return;
    rocks__set *full = (rocks__set *)set;
    rocks__set_free_arrays(full);
    core_free(full, sizeof *full);
}

/* ---- queries and export ----------------------------------------------------------------------- */

float rocks_hull_distance(const rocks_rock *rock, const float p[3], float normal[3]) {
    float best = -INFINITY;
    int best_axis = 0;
    float best_sign = 1.0f;
    for (int a = 0; a < ROCKS_HULL_AXES; a++) {
        const float *axis = rocks_hull_axes[a];
        float length = sqrtf(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
        float d = axis[0] * p[0] + axis[1] * p[1] + axis[2] * p[2];
        float above = (d - rock->hull[2 * a + 1]) / length, below = (rock->hull[2 * a] - d) / length;
        if (above > best) best = above, best_axis = a, best_sign = 1.0f;
        if (below > best) best = below, best_axis = a, best_sign = -1.0f;
    }
    if (normal) {
        const float *axis = rocks_hull_axes[best_axis];
        float length = sqrtf(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
        for (int a = 0; a < 3; a++) normal[a] = best_sign * axis[a] / length;
    }
    return best;
}

bool rocks_tile_write_ply(const rocks_tileset *set, int t, const char *path, core_error *error) {
    if (t < 0 || t > 255) return core_error_set(error, CORE_ERROR_RANGE, "tile %d is not 0 … 255", t);
    if (!set->vertices) return core_error_set(error, CORE_ERROR_ARGUMENT, "the set's meshes were released");
    const rocks_tile *tile = &set->tiles[t];
    size_t vertices = 0, triangles = 0;
    for (uint32_t e = tile->first; e < tile->first + tile->count; e++) {
        const rocks_rock *rock = &set->rocks[set->entries[e].rock];
        vertices += rock->vertex_count, triangles += rock->index_count[0] / 3;
    }
    char temp[4096];
    if (snprintf(temp, sizeof temp, "%s.tmp", path) >= (int)sizeof temp)
        return core_error_set(error, CORE_ERROR_ARGUMENT, "path too long: %s", path);
    FILE *f = fopen(temp, "wb");
    if (!f) return core_error_set(error, CORE_ERROR_IO, "cannot write %s: %s", temp, strerror(errno));
    fprintf(f, "ply\nformat binary_little_endian 1.0\ncomment rocks tile %d (paper 001), tile units\n"
               "element vertex %zu\nproperty float x\nproperty float y\nproperty float z\n"
               "property float nx\nproperty float ny\nproperty float nz\n"
               "element face %zu\nproperty list uchar uint vertex_indices\nend_header\n",
            t, vertices, triangles);
    for (uint32_t e = tile->first; e < tile->first + tile->count; e++) {
        const rocks_tile_entry *entry = &set->entries[e];
        const rocks_rock *rock = &set->rocks[entry->rock];
        for (uint32_t v = 0; v < rock->vertex_count; v++) {
            const rocks_vertex *vx = &set->vertices[rock->vertex_first + v];
            float out[6];
            for (int a = 0; a < 3; a++) out[a] = vx->position[a] + entry->offset[a], out[3 + a] = vx->normal[a] / 127.0f;
            fwrite(out, sizeof out, 1, f);
        }
    }
    uint32_t base = 0;
    for (uint32_t e = tile->first; e < tile->first + tile->count; e++) {
        const rocks_rock *rock = &set->rocks[set->entries[e].rock];
        const uint16_t *idx = set->indices + rock->index_first[0];
        for (uint32_t i = 0; i < rock->index_count[0]; i += 3) {
            unsigned char three = 3;
            uint32_t tri[3] = { base + idx[i], base + idx[i + 1], base + idx[i + 2] };
            fwrite(&three, 1, 1, f);
            fwrite(tri, sizeof tri, 1, f);
        }
        base += rock->vertex_count;
    }
    bool ok = !ferror(f);
    ok &= fclose(f) == 0;
    if (!ok || rename(temp, path) != 0) {
        remove(temp);
        return core_error_set(error, CORE_ERROR_IO, "cannot write %s", path);
    }
    return true;
}
