/* Sun shadows through OSMesa: a wall on flat ground under a sun 45° up, seen from straight above.
 * The wall's shadow falls where its height and the sun's elevation put it, and the ground the sun
 * reaches is as bright with shadows on as with them off (no acne). */
#include "../engine/test.h"
#include "render_util.h"

#include "ecs/ecs.h"
#include "jobs/jobs.h"
#include "terrain/terrain.h"
#include "terrain/render/terrain_render_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define W 384
#define H 216

/* Flat ground at GROUND_Y; a wall WALL_HEIGHT taller on columns x ∈ [14, 16), z ∈ [0, 32). */
#define GROUND_Y 4.0f
#define WALL_HEIGHT 8.0f
#define WALL_X0 14
#define WALL_X1 16
#define WALL_Z0 0
#define WALL_Z1 32

static void wall_column(void *user, int64_t x, int64_t z, terrain_stacks_builder *builder) {
    (void)user;
    bool wall = x >= WALL_X0 && x < WALL_X1 && z >= WALL_Z0 && z < WALL_Z1;
    terrain_stacks_builder_push(builder, TERRAIN_BEDROCK, GROUND_Y + (wall ? WALL_HEIGHT : 0.0f) - TERRAIN_FLOOR_Y);
}

static terrain_stacks *wall_chunk(void *user, terrain_chunk_coord coord) {
    return terrain_stacks_from_columns(coord, wall_column, user);
}

typedef struct wall_scene {
    gfx_context *gfx;
    job_system *jobs;
    ecs_world *ecs;
    terrain_world *world;
    terrain_ecs *te;
    terrain_view view;
} wall_scene;

/* The sun 45° up, shining towards −x: the wall's shadow lies on the ground from its foot at
 * x = 14 towards −x for WALL_HEIGHT / tan 45° = 8 m, x ∈ [6, 14], and only along the wall
 * (z ∈ [0, 32]): the sun has no z component. */
static wall_scene wall_open(void) {
    wall_scene s = { .gfx = render_offscreen(W, H) };
    s.jobs = job_system_create(&(job_system_desc){ .threads = 1 });
    s.ecs = ecs_world_create(&(ecs_world_desc){ .jobs = s.jobs });
    s.world = terrain_world_create(&(terrain_world_desc){ .generate = wall_chunk });
    s.te = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = s.ecs, .terrain = s.world });
    terrain_ecs_spawn_area(s.te, 0, 0, 1, 0, 0);
    /* 30 m above (10, 25), looking straight down (the top of the image towards −z): within the
     * reach of every quality's cascades (50 m for low) and short of low's fade. */
    s.view = (terrain_view){ .camera = { 10, GROUND_Y + 30, 25 }, .pitch = -1.5707f, .aspect = (float)W / H,
                             .sun_direction = { 1, 1, 0 } };
    terrain_ecs_set_view(s.te, &s.view);
    ecs_progress(s.ecs, 1.0f / 60.0f);
    return s;
}

static void wall_close(wall_scene *s) {
    terrain_ecs_destroy(s->te);
    ecs_world_destroy(s->ecs);
    terrain_world_destroy(s->world);
    job_system_destroy(s->jobs);
    gfx_context_destroy(s->gfx);
}

static render_image wall_draw(wall_scene *s, terrain_shadow_quality shadows) {
    /* Next to no fog: it would add the same sky colour to lit and shaded ground alike. */
    terrain_renderer *renderer = terrain_renderer_create(s->gfx, &(terrain_renderer_desc){
        .sea_level = -50, .fog_density = 1e-6f, .shadows = shadows, .no_occlusion = true });   /* shadows alone */
    cr_assert(renderer);
    gfx_frame_begin(s->gfx);
    terrain_ecs_draw(s->te, renderer, &s->view);
    render_image image = { W, H, malloc(W * H * 4) };
    gfx_read_pixels(s->gfx, image.rgba);
    gfx_frame_end(s->gfx);
    terrain_renderer_destroy(renderer);
    return image;
}

/* The pixel of a point on the ground (read_pixels' rows: the top first). */
static void ground_pixel(const wall_scene *s, double x, double z, int *px, int *py) {
    float m[16];
    terrain_view_matrix(&s->view, m);
    float p[3] = { (float)(x - s->view.camera[0]), (float)(GROUND_Y - s->view.camera[1]), (float)(z - s->view.camera[2]) };
    float clip[4];
    for (int r = 0; r < 4; r++) clip[r] = m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r];
    *px = (int)floor((clip[0] / clip[3] * 0.5 + 0.5) * W);
    *py = (int)floor((0.5 - clip[1] / clip[3] * 0.5) * H);
}

/* Mean luminance of the ground in x ∈ [x0, x1], z ∈ [z0, z1], over the pixels wholly inside. */
static double ground_mean(const wall_scene *s, const render_image *image, double x0, double x1, double z0, double z1) {
    int ax, ay, bx, by;
    ground_pixel(s, x0, z0, &ax, &ay);
    ground_pixel(s, x1, z1, &bx, &by);
    int left = (ax < bx ? ax : bx) + 1, right = (ax > bx ? ax : bx) - 1;
    int top = (ay < by ? ay : by) + 1, bottom = (ay > by ? ay : by) - 1;
    cr_assert(left >= 0 && right < W && top >= 0 && bottom < H && left < right && top < bottom,
              "region [%g, %g] × [%g, %g] is pixels [%d, %d] × [%d, %d]", x0, x1, z0, z1, left, right, top, bottom);
    double sum = 0;
    int count = 0;
    for (int y = top; y <= bottom; y++)
        for (int x = left; x <= right; x++, count++) sum += render_luminance(render_pixel(image, x, y));
    return sum / count;
}

/* Inside the footprint, a metre or two from its edges (the field rounds the wall's edges by a
 * column, and the filter softens the shadow's): x ∈ [8, 12], z ∈ [10, 26]. Beside it, the same
 * strip of ground past the wall's end, where nothing stands between it and the sun. */
#define SHADOW_REGION 8, 12, 10, 26
#define BESIDE_REGION 8, 12, 36, 41

Test(render_shadows, the_wall_shades_the_ground_it_hides_from_the_sun) {
    wall_scene s = wall_open();
    render_image off = wall_draw(&s, TERRAIN_SHADOWS_OFF), low = wall_draw(&s, TERRAIN_SHADOWS_LOW);
    double off_shadow = ground_mean(&s, &off, SHADOW_REGION), off_beside = ground_mean(&s, &off, BESIDE_REGION);
    double low_shadow = ground_mean(&s, &low, SHADOW_REGION), low_beside = ground_mean(&s, &low, BESIDE_REGION);
    /* Each strip is compared with itself without shadows: the ground's textures (and their 200 m
     * macro variation) differ from strip to strip, the light is what changes. Behind the wall
     * only the sky's ambient arrives: in common.glsl's light the sun's Lambert term on flat
     * ground under a 45° sun is about 0.7 of white against an ambient of about 0.15 (green, the
     * bulk of luminance), so the shadow is several times darker than the same ground lit. */
    cr_expect_lt(low_shadow, 0.5 * off_shadow, "behind the wall: %.1f with shadows, %.1f without", low_shadow,
                 off_shadow);
    cr_expect_lt(fabs(low_beside - off_beside), 0.02 * off_beside + 1, "lit strip: %.1f with shadows, %.1f without",
                 low_beside, off_beside);
    render_image_free(&off);
    render_image_free(&low);
    wall_close(&s);
}

Test(render_shadows, the_shadow_ends_where_the_sun_clears_the_wall) {
    wall_scene s = wall_open();
    render_image off = wall_draw(&s, TERRAIN_SHADOWS_OFF), low = wall_draw(&s, TERRAIN_SHADOWS_LOW);
    /* Past the tip of the shadow (x < 6 − a margin for the rounded top) the ground is lit again,
     * as bright as without shadows: the shadow is not stretched (peter-panning goes the other
     * way, detaching it from the foot, which the next check covers). */
    double past = ground_mean(&s, &low, 0, 4, 10, 26), past_off = ground_mean(&s, &off, 0, 4, 10, 26);
    cr_expect_lt(fabs(past - past_off), 0.05 * past_off, "past the shadow %.1f, without shadows %.1f", past, past_off);
    /* Right at the wall's foot (x ∈ [12, 13.5]) it is dark: no gap of light between the wall and
     * its shadow. */
    double foot = ground_mean(&s, &low, 12, 13.5, 10, 26), foot_off = ground_mean(&s, &off, 12, 13.5, 10, 26);
    cr_expect_lt(foot, 0.5 * foot_off, "at the wall's foot %.1f, without shadows %.1f", foot, foot_off);
    render_image_free(&off);
    render_image_free(&low);
    wall_close(&s);
}

Test(render_shadows, lit_ground_is_as_bright_with_shadows_as_without) {
    wall_scene s = wall_open();
    render_image off = wall_draw(&s, TERRAIN_SHADOWS_OFF), low = wall_draw(&s, TERRAIN_SHADOWS_LOW),
                 high = wall_draw(&s, TERRAIN_SHADOWS_HIGH);
    /* Open ground on both sides of the wall, away from its shadow: acne would darken it. */
    const double regions[2][4] = { { -18, 0, 10, 40 }, { 20, 38, 10, 40 } };
    for (int r = 0; r < 2; r++) {
        double a = ground_mean(&s, &off, regions[r][0], regions[r][1], regions[r][2], regions[r][3]);
        double b = ground_mean(&s, &low, regions[r][0], regions[r][1], regions[r][2], regions[r][3]);
        double c = ground_mean(&s, &high, regions[r][0], regions[r][1], regions[r][2], regions[r][3]);
        cr_expect_lt(fabs(b - a), 0.01 * a + 0.5, "region %d: %.2f low, %.2f off", r, b, a);
        cr_expect_lt(fabs(c - a), 0.01 * a + 0.5, "region %d: %.2f high, %.2f off", r, c, a);
    }
    /* And pixel by pixel there: the worst pixel within a few levels. */
    int worst = 0;
    int ax, ay, bx, by;
    ground_pixel(&s, -18, 10, &ax, &ay);
    ground_pixel(&s, 0, 40, &bx, &by);
    for (int y = (ay < by ? ay : by) + 1; y < (ay > by ? ay : by); y++)
        for (int x = (ax < bx ? ax : bx) + 1; x < (ax > bx ? ax : bx); x++) {
            int d = abs((int)render_luminance(render_pixel(&low, x, y)) - (int)render_luminance(render_pixel(&off, x, y)));
            if (d > worst) worst = d;
        }
    cr_expect_leq(worst, 3, "worst pixel of lit ground differs by %d", worst);
    render_image_free(&off);
    render_image_free(&low);
    render_image_free(&high);
    wall_close(&s);
}

/* A low-shadows renderer (or one without shadows) with next to no fog, occlusion off. */
static terrain_renderer *wall_renderer(wall_scene *s, terrain_shadow_quality shadows) {
    terrain_renderer *renderer = terrain_renderer_create(s->gfx, &(terrain_renderer_desc){
        .sea_level = -50, .fog_density = 1e-6f, .shadows = shadows, .no_occlusion = true });
    cr_assert(renderer);
    return renderer;
}

/* The camera moved to x (the view otherwise as it is), one frame of the ECS, and a frame drawn
 * with `renderer`; its pixels into `image` when not NULL. */
static void wall_frame_at(wall_scene *s, double x, terrain_renderer *renderer, render_image *image) {
    s->view.camera[0] = x;
    terrain_ecs_set_view(s->te, &s->view);
    ecs_progress(s->ecs, 1.0f / 60.0f);
    gfx_frame_begin(s->gfx);
    terrain_ecs_draw(s->te, renderer, &s->view);
    if (image) gfx_read_pixels(s->gfx, image->rgba);
    gfx_frame_end(s->gfx);
}

/* The maps follow the camera: a cascade is redrawn only when its box moved or its casters
 * changed, at most one a frame, and the receivers read each where it was drawn. With the camera
 * sliding 3 m a frame (every box moves), the shadow stays under the wall in every frame. */
Test(render_shadows, the_shadow_stays_put_while_the_camera_moves) {
    wall_scene s = wall_open();
    terrain_renderer *renderer = wall_renderer(&s, TERRAIN_SHADOWS_LOW);
    terrain_renderer *unshadowed = wall_renderer(&s, TERRAIN_SHADOWS_OFF);
    render_image image = { W, H, malloc(W * H * 4) }, lit = { W, H, malloc(W * H * 4) };
    for (int frame = 0; frame < 5; frame++) {
        wall_frame_at(&s, 10.0 + 3.0 * frame, unshadowed, &lit);
        wall_frame_at(&s, 10.0 + 3.0 * frame, renderer, &image);
        double shadow = ground_mean(&s, &image, SHADOW_REGION), shadow_lit = ground_mean(&s, &lit, SHADOW_REGION);
        double past = ground_mean(&s, &image, 0, 4, 10, 26), past_lit = ground_mean(&s, &lit, 0, 4, 10, 26);
        cr_expect_lt(shadow, 0.5 * shadow_lit, "frame %d: %.1f behind the wall, %.1f unshadowed", frame, shadow,
                     shadow_lit);
        cr_expect_lt(fabs(past - past_lit), 0.05 * past_lit, "frame %d: past the shadow %.1f, unshadowed %.1f", frame,
                     past, past_lit);
    }
    render_image_free(&lit);
    terrain_renderer_destroy(unshadowed);
    render_image_free(&image);
    terrain_renderer_destroy(renderer);
    wall_close(&s);
}

/* A map nothing casts into is the same wherever its box is: looking up from above the wall (every
 * mesh below the view, so nothing can shade what it sees) with the camera sliding 3 m a frame
 * (past either box's guard band every frame or three), the two cascades are drawn once and not
 * again. Looking down, the far cascade holds the ground and the wall: it is drawn when the wall
 * comes in, and again when its box is left behind (8.3 m of band; the near cascade, 0.1–12 m
 * below the eye and 30 m above the ground, stays empty). */
Test(render_shadows, an_empty_map_is_not_redrawn_as_the_camera_moves) {
    wall_scene s = wall_open();
    terrain_renderer *renderer = wall_renderer(&s, TERRAIN_SHADOWS_LOW);
    const terrain__shadows *shadows = terrain__renderer_shadows(renderer);
    cr_assert(shadows);
    for (int look_up = 1; look_up >= 0; look_up--) {
        s.view.pitch = look_up ? 1.5707f : -1.5707f;
        uint64_t before = terrain__shadows_cascades_drawn(shadows);
        for (int frame = 0; frame < 6; frame++) wall_frame_at(&s, 10.0 + 3.0 * frame, renderer, NULL);
        uint64_t drawn = terrain__shadows_cascades_drawn(shadows) - before;
        if (look_up) cr_expect_eq(drawn, 2, "looking up: %llu cascades drawn in 6 frames, expected the first 2",
                                  (unsigned long long)drawn);
        else cr_expect_geq(drawn, 2, "looking down at the wall: %llu cascades drawn in 6 frames",
                           (unsigned long long)drawn);
    }
    terrain_renderer_destroy(renderer);
    wall_close(&s);
}

/* A box wider than its slice stays where it was drawn while the slice stays inside it: walking
 * pace (0.1 m a frame, 6 m/s at 60 frames a second) for ten frames draws the two cascades once,
 * where a box that follows the camera texel by texel (2.8 cm for the near cascade here) would draw
 * one every frame; and the shadow is still under the wall at the end. */
Test(render_shadows, a_walking_camera_keeps_its_maps) {
    wall_scene s = wall_open();
    terrain_renderer *renderer = wall_renderer(&s, TERRAIN_SHADOWS_LOW);
    terrain_renderer *unshadowed = wall_renderer(&s, TERRAIN_SHADOWS_OFF);
    const terrain__shadows *shadows = terrain__renderer_shadows(renderer);
    render_image image = { W, H, malloc(W * H * 4) }, lit = { W, H, malloc(W * H * 4) };
    for (int frame = 0; frame < 10; frame++) wall_frame_at(&s, 10.0 + 0.1 * frame, renderer, &image);
    cr_expect_eq(terrain__shadows_cascades_drawn(shadows), 2, "%llu cascades drawn in 10 frames at walking pace",
                 (unsigned long long)terrain__shadows_cascades_drawn(shadows));
    wall_frame_at(&s, s.view.camera[0], unshadowed, &lit);
    double shadow = ground_mean(&s, &image, SHADOW_REGION), shadow_lit = ground_mean(&s, &lit, SHADOW_REGION);
    cr_expect_lt(shadow, 0.5 * shadow_lit, "%.1f behind the wall, %.1f unshadowed", shadow, shadow_lit);
    render_image_free(&lit);
    render_image_free(&image);
    terrain_renderer_destroy(unshadowed);
    terrain_renderer_destroy(renderer);
    wall_close(&s);
}
