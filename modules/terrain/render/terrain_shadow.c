/* terrain_shadow.c — the sun's cascaded shadow map (shaders/shadow.*; the receivers' side is
 * shadow.glsl). Main thread only.
 *
 * Cascades. The view's depth is split at fixed distances; each slice of the frustum is enclosed
 * in its bounding sphere, and the cascade is an orthographic box along the sun around that
 * sphere. A sphere does not change size as the view turns, so the box keeps one size, and its
 * centre is snapped to whole texels along the light's axes in world coordinates (doubles): the
 * texels sit still on the ground as the camera moves and turns, and shadow edges do not swim.
 * The boxes hold more than the slices (a sphere is rounder than a frustum slice) in exchange.
 *
 * Everything stays camera-relative as the terrain draws it: the matrices take camera-relative
 * positions, their translations worked out in double, so the map is as sharp 100 km out.
 *
 * Casters above a box (towards the sun) are clamped onto its near plane (GL_DEPTH_CLAMP), so the
 * box need not reach up to every hill that may shade it. Acne: the lookup moves off the surface
 * along its normal by about a texel of its cascade (shadow.glsl), and the casters are drawn with
 * a slope-scaled polygon offset; both are small enough that a wall's shadow still meets its foot.
 */
#include "terrain/render/terrain_render.h"
#include "terrain/render/terrain_render_internal.h"

#include "core/core.h"
#include "gfx/gfx.h"
#include "trace/trace.h"

#include <math.h>
#include <string.h>

#define SHADOW_MAX_CASCADES 4

typedef struct shadow_settings {
    int cascades, size, taps;
    float splits[SHADOW_MAX_CASCADES];       /* far end of each slice, metres along the view */
} shadow_settings;

/* On llvmpipe the lookups are most of the cost (each bilinear tap is four texel fetches and
 * compares for every lit pixel), then clearing the maps: low keeps to one bilinear tap (2 × 2
 * texels) on two small maps; high has a third, wider cascade, four times the texels and 3 × 3
 * taps (a 4 × 4 texel footprint, softer edges). */
static const shadow_settings shadow_low = { 2, 1024, 1, { 12.0f, 50.0f } };
static const shadow_settings shadow_high = { 3, 2048, 3, { 16.0f, 64.0f, 300.0f } };

/* The receiver's lookup moves this many texels of its cascade along its normal. */
#define SHADOW_NORMAL_OFFSET_TEXELS 1.5f
/* The box reaches this many sphere radii above its sphere (towards the sun) before the clamp. */
#define SHADOW_REACH_ABOVE 1.0
/* Each box is wider than its slice's sphere by this share of the radius each way, and stays where
 * it was drawn while the sphere stays inside it: walking at 4.5 m/s the near cascade is redrawn
 * about every 0.4 s instead of every texel's worth of motion (every frame or two), for 11 % fewer
 * texels across the slice. */
#define SHADOW_GUARD 0.125

typedef struct shadow_cascade {
    gfx_framebuffer framebuffer;             /* depth into the map's layer of this cascade */
    /* Where the box is in the world: its centre on the light's axes, snapped to texels. The map
     * holds what was drawn there; the matrices below follow the camera every frame. */
    double light[3];
    double radius, depth_bottom;             /* half the box's side; its far side along the sun */
    float normal_offset;                     /* metres */
    uint64_t key;                            /* the box and the serials of what cast into it */
    bool drawn;                              /* the map layer holds this box's casters */
    /* This frame's, from the camera: */
    float texture_matrix[16];                /* camera-relative → (u, v, depth) in [0, 1] */
    float clip_matrix[16];                   /* camera-relative → the cascade's clip space */
    double centre[3];                        /* the box's centre, camera-relative (culling) */
    double planes[6][4];                     /* the view's slice, camera-relative, inside ≥ 0 */
} shadow_cascade;

struct terrain__shadows {
    gfx_context *gfx;
    float forward[3];                        /* the view's axis: receivers pick a cascade by depth */
    gfx_program program;
    gfx_texture texture;                     /* one depth layer per cascade */
    shadow_settings settings;
    shadow_cascade cascades[SHADOW_MAX_CASCADES];
    double right[3], up[3], sun[3];          /* the light's axes (world = camera-relative) */
    int cascades_ready;                      /* every layer drawn: the receivers may read them */
    int next;                                /* the cascade whose turn it is to be redrawn */
    uint64_t cascades_drawn;                 /* since creation (tests; the trace counts a frame's) */
};

bool terrain_parse_shadow_quality(const char *text, terrain_shadow_quality *out) {
    static const char *const names[] = { "off", "low", "high" };
    for (int q = 0; q < 3; q++)
        if (text && strcmp(text, names[q]) == 0) {
            *out = (terrain_shadow_quality)(TERRAIN_SHADOWS_OFF + q);
            return true;
        }
    return false;
}

const char *terrain_shadow_quality_name(terrain_shadow_quality quality) {
    switch (quality) {
    case TERRAIN_SHADOWS_OFF: return "off";
    case TERRAIN_SHADOWS_HIGH: return "high";
    default: return "low";
    }
}

terrain__shadows *terrain__shadows_create(gfx_context *gfx, terrain_shadow_quality quality) {
    if (quality == TERRAIN_SHADOWS_OFF) return NULL;
    gfx_program program = gfx_program_load(gfx, "shadow.vert", "shadow.frag");
    if (!program.id) return NULL;
    terrain__shadows *s = core_calloc(1, sizeof *s);
    s->gfx = gfx;
    s->program = program;
    s->settings = quality == TERRAIN_SHADOWS_HIGH ? shadow_high : shadow_low;
    int size = s->settings.size;
    /* Linear filtering on a comparing sampler: each lookup is a bilinear 2 × 2 PCF for free. */
    s->texture = gfx_texture_create(&(gfx_texture_desc){ .width = size, .height = size,
        .layers = s->settings.cascades, .array = true, .format = GFX_FORMAT_DEPTH32F, .clamp = true,
        .compare = true });
    for (int c = 0; c < s->settings.cascades; c++) {
        s->cascades[c].framebuffer = gfx_framebuffer_create(&(gfx_framebuffer_desc){
            .width = size, .height = size, .depth_only = true, .depth_texture = s->texture, .depth_layer = c });
        if (!s->cascades[c].framebuffer.id) {
            core_log_error("terrain", "the shadow map's depth target is incomplete; shadows off");
            terrain__shadows_destroy(s);
            return NULL;
        }
    }
    return s;
}

void terrain__shadows_destroy(terrain__shadows *s) {
    if (!s) return;
    for (int c = 0; c < s->settings.cascades; c++) gfx_framebuffer_destroy(&s->cascades[c].framebuffer);
    gfx_texture_destroy(&s->texture);
    core_free(s, sizeof *s);
}

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* Axes across the light (right, up) and along it (towards the sun): fixed for a sun, so the
 * texel grid in the world is too. */
static void shadow_axes(terrain__shadows *s, const float sun[3]) {
    double d[3] = { sun[0], sun[1], sun[2] };
    double ref[3] = { 0, 1, 0 };
    if (fabs(d[1]) > 0.99) ref[1] = 0, ref[2] = 1;     /* the sun overhead: any other axis */
    double r[3] = { d[1] * ref[2] - d[2] * ref[1], d[2] * ref[0] - d[0] * ref[2], d[0] * ref[1] - d[1] * ref[0] };
    double length = sqrt(dot3(r, r));
    for (int a = 0; a < 3; a++) r[a] /= length;
    /* up = sun × right, so that right × up = sun: the light's view is not mirrored and the
     * meshes' winding tells faces towards the sun from faces away from it. */
    double u[3] = { d[1] * r[2] - d[2] * r[1], d[2] * r[0] - d[0] * r[2], d[0] * r[1] - d[1] * r[0] };
    if (memcmp(s->sun, d, sizeof d) != 0)
        for (int c = 0; c < SHADOW_MAX_CASCADES; c++) s->cascades[c].drawn = false;
    memcpy(s->right, r, sizeof r);
    memcpy(s->up, u, sizeof u);
    memcpy(s->sun, d, sizeof d);
}

/* The bounding sphere of the frustum slice [near, far] along the view: its centre's distance
 * along the view axis and its radius. A slice's corners lie k·d off the axis at distance d
 * (k² = tan²(fov_x/2) + tan²(fov_y/2)); the centre that makes the near and far corners equally
 * far is at (near + far)(1 + k²)/2, or the far end when that lies beyond it. */
static void shadow_slice_sphere(double near, double far, double k2, double *centre, double *radius) {
    double c = 0.5 * (near + far) * (1.0 + k2);
    if (c >= far) {
        *centre = far;
        *radius = far * sqrt(k2);
    } else {
        *centre = c;
        *radius = sqrt((far - c) * (far - c) + far * far * k2);
    }
}

/* Row-major 4 × 3 rows into a column-major mat4 with (0, 0, 0, 1) as its last row. */
static void shadow_matrix(const double rows[3][4], float out[16]) {
    for (int row = 0; row < 3; row++)
        for (int col = 0; col < 4; col++) out[col * 4 + row] = (float)rows[row][col];
    out[3] = out[7] = out[11] = 0.0f;
    out[15] = 1.0f;
}

/* This frame's matrices of a cascade placed at cascade->light, from the camera. */
static void shadow_place(const terrain__shadows *s, shadow_cascade *cascade, const double camera[3]) {
    double radius = cascade->radius;
    /* Offsets of the camera from the box's centre along each axis, in double. */
    double ox = dot3(camera, s->right) - cascade->light[0], oy = dot3(camera, s->up) - cascade->light[1],
           oz = dot3(camera, s->sun) - cascade->light[2];
    double top = radius * (1.0 + SHADOW_REACH_ABOVE), bottom = cascade->depth_bottom, range = top - bottom;
    const double *axes[3] = { s->right, s->up, s->sun };
    double rows[3][4];
    for (int a = 0; a < 3; a++) {
        rows[0][a] = axes[0][a] * 0.5 / radius;
        rows[1][a] = axes[1][a] * 0.5 / radius;
        rows[2][a] = -axes[2][a] / range;
    }
    rows[0][3] = 0.5 + 0.5 * ox / radius;
    rows[1][3] = 0.5 + 0.5 * oy / radius;
    rows[2][3] = (top - oz) / range;
    shadow_matrix(rows, cascade->texture_matrix);
    for (int r = 0; r < 3; r++) {                /* [0, 1] → [−1, 1]: clip = 2·t − 1 */
        for (int a = 0; a < 3; a++) rows[r][a] *= 2.0;
        rows[r][3] = 2.0 * rows[r][3] - 1.0;
    }
    shadow_matrix(rows, cascade->clip_matrix);
    for (int a = 0; a < 3; a++) cascade->centre[a] = -(ox * s->right[a] + oy * s->up[a] + oz * s->sun[a]);
}

/* Where each cascade's box should be for this view (into `wanted`, placed for the camera), and
 * the slice planes its casters are culled by. */
static void shadow_fit(terrain__shadows *s, const terrain_view *view, shadow_cascade wanted[]) {
    const shadow_settings *set = &s->settings;
    float fov_y = view->fov_y > 0 ? view->fov_y : 1.04719755f;
    float aspect = view->aspect > 0 ? view->aspect : 16.0f / 9.0f;
    double ty = tan(0.5 * (double)fov_y), tx = ty * (double)aspect, k2 = tx * tx + ty * ty;
    double cos_pitch = cos((double)view->pitch);
    double forward[3] = { sin((double)view->yaw) * cos_pitch, sin((double)view->pitch),
                          -cos((double)view->yaw) * cos_pitch };
    terrain_frustum frustum = terrain_frustum_from_view(view);
    for (int a = 0; a < 3; a++) s->forward[a] = (float)forward[a];
    double near = 0.1;
    for (int c = 0; c < set->cascades; c++) {
        shadow_cascade *cascade = &wanted[c];
        *cascade = s->cascades[c];
        /* The view's side planes, and its depth cut to this slice. */
        for (int p = 0; p < 4; p++)
            for (int k = 0; k < 4; k++) cascade->planes[p][k] = frustum.planes[p][k];
        for (int a = 0; a < 3; a++) {
            cascade->planes[4][a] = forward[a];
            cascade->planes[5][a] = -forward[a];
        }
        cascade->planes[4][3] = -near;
        cascade->planes[5][3] = set->splits[c];
        double along, radius;
        shadow_slice_sphere(near, set->splits[c], k2, &along, &radius);
        near = set->splits[c];
        double box = radius * (1.0 + SHADOW_GUARD), texel = 2.0 * box / set->size;
        /* The sphere's centre on the light's axes. The box stays where it was drawn while the
         * sphere is inside it; otherwise it is centred on the sphere, snapped to whole texels
         * (along the light too, so that a box that has not moved is the same box, bit for bit). */
        double world[3], at[3];
        for (int a = 0; a < 3; a++) world[a] = view->camera[a] + forward[a] * along;
        at[0] = dot3(world, s->right), at[1] = dot3(world, s->up), at[2] = dot3(world, s->sun);
        const shadow_cascade *held = &s->cascades[c];
        bool inside = held->drawn && held->radius == box;
        for (int a = 0; a < 3; a++) inside = inside && fabs(at[a] - held->light[a]) <= box - radius;
        for (int a = 0; a < 3; a++) cascade->light[a] = inside ? held->light[a] : floor(at[a] / texel) * texel;
        cascade->radius = box;
        cascade->depth_bottom = -box - texel;     /* the snap along the light moved it ≤ a texel */
        cascade->normal_offset = (float)(SHADOW_NORMAL_OFFSET_TEXELS * texel);
        shadow_place(s, cascade, view->camera);
    }
}

/* Whether a mesh's box can shade anything the cascade's slice of the view holds. Its shadow is
 * the box swept away from the sun, so the box is out when it lies wholly across the light from
 * the cascade's box, or wholly outside one of the slice's planes that the sweep cannot cross
 * (the plane's inside does not lie further from the sun). Most of a big cascade's box is beside
 * the view: these tests keep the casters near to what is seen, which is what llvmpipe's triangle
 * setup pays for. */
static bool shadow_cascade_sees_box(const terrain__shadows *s, const shadow_cascade *cascade, const double camera[3],
                                    const double origin[3], const float box_lo[3], const float box_hi[3]) {
    double lo[3], hi[3], centre[3], half[3];
    for (int a = 0; a < 3; a++) {
        lo[a] = origin[a] - camera[a] + box_lo[a];
        hi[a] = origin[a] - camera[a] + box_hi[a];
        centre[a] = 0.5 * (lo[a] + hi[a]) - cascade->centre[a];
        half[a] = 0.5 * (hi[a] - lo[a]);
    }
    const double *axes[3] = { s->right, s->up, s->sun };
    for (int k = 0; k < 3; k++) {
        double reach = fabs(axes[k][0]) * half[0] + fabs(axes[k][1]) * half[1] + fabs(axes[k][2]) * half[2];
        double at = dot3(centre, axes[k]);
        if (k < 2 && fabs(at) - reach > cascade->radius) return false;
        if (k == 2 && at + reach < cascade->depth_bottom) return false;
    }
    for (int p = 0; p < 6; p++) {
        const double *plane = cascade->planes[p];
        if (dot3(plane, s->sun) < 0) continue;   /* away from the sun lies inside: the sweep enters */
        double x = plane[0] >= 0 ? hi[0] : lo[0], y = plane[1] >= 0 ? hi[1] : lo[1], z = plane[2] >= 0 ? hi[2] : lo[2];
        if (plane[0] * x + plane[1] * y + plane[2] * z + plane[3] < 0) return false;
    }
    return true;
}

static bool shadow_cascade_sees(const terrain__shadows *s, const shadow_cascade *cascade, const double camera[3],
                                const terrain_gpu_mesh *mesh) {
    return shadow_cascade_sees_box(s, cascade, camera, mesh->origin, mesh->bounds_min, mesh->bounds_max);
}

/* What terrain__draw_parts asks of a part. */
typedef struct shadow_part_test {
    const terrain__shadows *shadows;
    const shadow_cascade *cascade;
    const double *camera;
} shadow_part_test;

static bool shadow_part_sees(const void *user, const double origin[3], const float lo[3], const float hi[3]) {
    const shadow_part_test *t = user;
    return shadow_cascade_sees_box(t->shadows, t->cascade, t->camera, origin, lo, hi);
}

static uint64_t shadow_key_double(uint64_t key, double value) {
    uint64_t bits;
    memcpy(&bits, &value, sizeof bits);
    return core_hash_combine(key, core_hash_u64(bits));
}

/* The key of a map that nothing casts into: an empty map is the same wherever its box is. */
#define SHADOW_EMPTY_KEY 0x5ad0e3b7c1f20a49ull

/* The box and the serials of the meshes that cast into it: the same key, the same map. A box
 * that no mesh casts into has the one empty key, so an empty map is not redrawn as its box
 * follows the camera (from high above the ground, or looking up, every frame would redraw both
 * empty maps: on llvmpipe a pass, a clear and a wait for them before the terrain reads them). */
static uint64_t shadow_cascade_key(const terrain__shadows *s, const shadow_cascade *cascade, const double camera[3],
                                   const terrain_gpu_mesh *casters, int caster_count) {
    uint64_t key = core_hash_u64((uint64_t)caster_count);
    for (int a = 0; a < 3; a++) key = shadow_key_double(key, cascade->light[a]);
    key = shadow_key_double(key, cascade->radius);
    bool any = false;
    for (int i = 0; i < caster_count; i++)
        if (casters[i].index_count && shadow_cascade_sees(s, cascade, camera, &casters[i])) {
            key = core_hash_combine(key, core_hash_u64(casters[i].serial));
            any = true;
        }
    return any ? key : SHADOW_EMPTY_KEY;
}

static void shadow_draw_cascade(terrain__shadows *s, shadow_cascade *cascade, const double camera[3],
                                const terrain_gpu_mesh *casters, int caster_count) {
    glBindFramebuffer(GL_FRAMEBUFFER, gfx_framebuffer_gl(cascade->framebuffer));
    glDepthMask(GL_TRUE);
    glClear(GL_DEPTH_BUFFER_BIT);
    gfx_uniform_mat4(s->gfx, s->program, "u_light_projection", cascade->clip_matrix);
    GLuint gl = gfx_program_gl(s->gfx, s->program);
    GLint offset_location = glGetUniformLocation(gl, "u_offset");
    for (int i = 0; i < caster_count; i++) {
        const terrain_gpu_mesh *m = &casters[i];
        if (m->index_count == 0 || !shadow_cascade_sees(s, cascade, camera, m)) continue;
        float offset[3];
        for (int a = 0; a < 3; a++) offset[a] = (float)(m->origin[a] - camera[a]);
        glProgramUniform3fv(gl, offset_location, 1, offset);
        terrain__draw_parts(m, shadow_part_sees, &(shadow_part_test){ s, cascade, camera });
    }
    cascade->drawn = true;
    s->cascades_drawn++;
}

/* A cascade is redrawn only when its box moved (the view's slice left it: shadow_fit) or
 * what casts into it changed, and, once every layer holds something, at most one cascade a
 * frame, in turns: on llvmpipe the casters' triangles are most of the pass, and a layer a frame
 * late (the receivers still read it where it was drawn) is not to be seen. */
void terrain__shadows_render(terrain__shadows *s, const terrain_view *view, const float sun[3],
                             const terrain_gpu_mesh *casters, int caster_count) {
    TRACE_ZONE("terrain_shadows");
    const shadow_settings *set = &s->settings;
    shadow_axes(s, sun);
    shadow_cascade wanted[SHADOW_MAX_CASCADES];
    shadow_fit(s, view, wanted);
    bool all_drawn = true, redraw[SHADOW_MAX_CASCADES] = { false };
    for (int c = 0; c < set->cascades; c++) {
        wanted[c].key = shadow_cascade_key(s, &wanted[c], view->camera, casters, caster_count);
        redraw[c] = !s->cascades[c].drawn || wanted[c].key != s->cascades[c].key;
        all_drawn = all_drawn && s->cascades[c].drawn;
    }
    if (all_drawn) {                          /* one a frame: the next in turn that changed */
        int chosen = -1;
        for (int k = 0; k < set->cascades && chosen < 0; k++)
            if (redraw[(s->next + k) % set->cascades]) chosen = (s->next + k) % set->cascades;
        for (int c = 0; c < set->cascades; c++) redraw[c] = c == chosen;
        if (chosen >= 0) s->next = (chosen + 1) % set->cascades;
    }
    int first = -1, redrawn = 0;
    for (int c = 0; c < set->cascades; c++) {
        if (redraw[c]) {
            s->cascades[c] = wanted[c];
            if (first < 0) first = c;
            redrawn++;
        } else {
            /* Kept where it was drawn; this frame's matrices, this frame's slice for culling. */
            memcpy(s->cascades[c].planes, wanted[c].planes, sizeof wanted[c].planes);
            shadow_place(s, &s->cascades[c], view->camera);
        }
    }
    trace_counter("terrain.shadow_cascades_drawn", redrawn);
    if (first >= 0) {
        gfx_pass_begin(s->gfx, &(gfx_pass_desc){ .name = "shadows", .target = s->cascades[first].framebuffer });
        glEnable(GL_DEPTH_CLAMP);
        glEnable(GL_POLYGON_OFFSET_FILL);
        glPolygonOffset(1.5f, 2.0f);
        /* Only faces turned away from the sun cast: the ground is a closed solid seen from
         * above, so its shadows' edges are those faces' edges, and a sunlit face never meets its
         * own depth in the map (no acne where the light reaches; the faces that do cast get no
         * sun to shade). It also halves what the map rasterises. */
        glCullFace(GL_FRONT);
        gfx_program_use(s->gfx, s->program);
        for (int c = 0; c < set->cascades; c++)
            if (redraw[c]) shadow_draw_cascade(s, &s->cascades[c], view->camera, casters, caster_count);
        glCullFace(GL_BACK);
        glDisable(GL_POLYGON_OFFSET_FILL);
        glDisable(GL_DEPTH_CLAMP);
        gfx_pass_end(s->gfx);
    }
    s->cascades_ready = 0;
    for (int c = 0; c < set->cascades; c++) s->cascades_ready += s->cascades[c].drawn;
    if (s->cascades_ready < set->cascades) s->cascades_ready = 0;
}

uint64_t terrain__shadows_cascades_drawn(const terrain__shadows *s) { return s ? s->cascades_drawn : 0; }

void terrain__shadows_bind(const terrain__shadows *s, gfx_context *gfx, uint32_t program_handle, int unit) {
    gfx_program program = { program_handle };
    gfx_uniform_int(gfx, program, "u_shadow_map", unit);
    int cascades = s ? s->cascades_ready : 0;
    gfx_uniform_int(gfx, program, "u_shadow_cascades", cascades);
    if (!cascades) return;
    GLuint gl = gfx_program_gl(gfx, program);
    float matrices[SHADOW_MAX_CASCADES * 16], offsets[SHADOW_MAX_CASCADES];
    for (int c = 0; c < cascades; c++) {
        memcpy(matrices + c * 16, s->cascades[c].texture_matrix, sizeof s->cascades[c].texture_matrix);
        offsets[c] = s->cascades[c].normal_offset;
    }
    glProgramUniformMatrix4fv(gl, glGetUniformLocation(gl, "u_shadow_matrix"), cascades, GL_FALSE, matrices);
    glProgramUniform1fv(gl, glGetUniformLocation(gl, "u_shadow_normal_offset"), cascades, offsets);
    glProgramUniform1fv(gl, glGetUniformLocation(gl, "u_shadow_splits"), cascades, s->settings.splits);
    gfx_uniform_vec3(gfx, program, "u_shadow_forward", s->forward);
    gfx_uniform_float(gfx, program, "u_shadow_texel", 1.0f / (float)s->settings.size);
    gfx_uniform_int(gfx, program, "u_shadow_taps", s->settings.taps);
    gfx_texture_bind(s->texture, unit);
}
