/* app.c — the walkable world's frame loop (app.h). */
#include "app.h"

#include "core/core.h"
#include "ecs/ecs.h"
#include "gfx/gfx.h"
#include "input/input.h"
#include "jobs/jobs.h"
#include "player.h"
#include "screenshot.h"
#include "tools.h"
#include "trace/trace.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <sys/resource.h>
#include <unistd.h>

#define APP_REPLAY_STABILIZE_ITERATIONS 3   /* per frame when recording, replaying or walking */
#define APP_HITCH_MS 33.0
#define APP_PI 3.14159265358979323846

struct game_app {
    game_app_desc desc;
    gfx_context *gfx;
    job_system *jobs;
    ecs_world *ecs;
    terrain_world *world;
    terrain_renderer *renderer;
    terrain_clipmap *clipmap;              /* the far terrain, or NULL */
    terrain_ecs *terrain;
    grass_system *grass;                   /* NULL with --grass off */
    rocks_tileset *own_rock_tiles;         /* the default set, when desc.rock_tiles is NULL */
    const rocks_tileset *rock_tiles;       /* NULL with --rocks off */
    rocks_system *rocks;
    rocks_cliffs *cliffs;                  /* NULL with desc.cliffs off */
    terrain_water *water;                  /* NULL with --water off */
    input_bindings *bindings;
    input_system *input;
    gfx_text *hud;
    game_ids ids;                          /* the game's components and resources (app.h) */
    ecs_entity player_entity, camera_entity;
    game_walker walker;
    game_walk walk;                        /* the app's copy of desc.walk: its cave lines resolved */
    game_tools tools;
    terrain_edit_log *edits;               /* every edit; loaded and saved with a world folder */
    terrain_store *store;                  /* the world folder's database, or NULL */
    uint64_t last_save_ns;
    bool windowed, interactive, loading, over;
    bool running;                          /* false once input says quit (or a replay ran out) */
    bool screenshot_wanted;                /* F12 this frame: taken once the frame is drawn */
    uint64_t drawing_ns;                   /* this frame's draw calls began */
    uint64_t screenshot_ns;                /* this frame's pictures took (left out of its CPU time) */
    bool spawned;                          /* the player stands in the world (its pose is saved) */
    bool holding;                          /* the view desc.at/look asked for, until input moves it */
    bool hud_hidden;                       /* F1 (toggle_hud) */
    char hud_note[300];                    /* a passing message ("screenshot: …"), shown a few seconds */
    uint64_t hud_note_ns;                  /* when it was set */
    uint64_t play_start_ns;                /* when loading ended: the hint's clock */
    int frames, loading_frames;
    int screen_height;                     /* framebuffer height and fov the detail was derived */
    float screen_fov_y;                    /* for (app_screen_changed); 0 = not yet */
    uint64_t start_ns, last_ns;
    double frame_seconds;
    double *cpu_ms, *engine_ms, *thread_ms; /* per frame past loading */
    double *triangles;                      /* drawn per frame past loading (gfx_context_stats) */
    size_t cpu_count, cpu_capacity, engine_capacity, thread_capacity, triangles_capacity;
    int eye_in_solid, waiting;
    double grass_ms_sum, grass_ms_max;     /* past loading */
    /* pictures at the walk's `shot` waypoints (walk.h): held frames, and each picture at half
     * size for the contact sheet */
    int shot_hold;
    struct app_shot { uint8_t *rgba; int width, height; } *shots;   /* each at half size */
    int shot_count;
    size_t shot_capacity;
};

/* The player's body and the main camera's view. Outside systems or inside one that declared
 * them (ecs.h, ACCESS). */
static game_player *app_player(const game_app *app) {
    return &((GamePlayer *)ecs_get(app->ecs, app->player_entity, app->ids.player))->body;
}

static terrain_view *app_view(const game_app *app) {
    return &((GameCamera *)ecs_get(app->ecs, app->camera_entity, app->ids.camera))->view;
}

/* After the player is put somewhere (spawned, restored, a walk's start): nothing to interpolate
 * from, so the camera starts there. */
static void app_player_placed(game_app *app) {
    GamePlayer *player = ecs_get(app->ecs, app->player_entity, app->ids.player);
    memcpy(player->previous, player->body.position, sizeof player->previous);
}

static void app_create_entities(game_app *app);
static void app_add_systems(game_app *app);

/* The player waits at the edge of what has streamed in (interactive play only, see app.h). */
static bool app_region_ready(void *user, const double min[3], const double max[3]) {
    game_app *app = user;
    return terrain_ecs_region_ready(app->terrain, min, max);
}

/* The rocks as obstacles for the player's capsule and the tools' aim (player.h, tools.h). */
static void app_rocks_near(void *user, const double min[3], const double max[3]) {
    rocks_focus(user, min, max);
}

static float app_rock_distance(void *user, const double point[3], float max_distance, float normal[3]) {
    return rocks_distance(user, point, max_distance, normal);
}

static bool app_rock_raycast(void *user, const double origin[3], const float direction[3], float max_distance,
                             terrain_ray_hit *hit) {
    rocks_ray_hit r;
    if (!rocks_raycast(user, origin, direction, max_distance, &r)) return false;
    *hit = (terrain_ray_hit){ .position = { r.position[0], r.position[1], r.position[2] },
                              .normal = { r.normal[0], r.normal[1], r.normal[2] }, .distance = r.distance,
                              .material = TERRAIN_ROCKS };
    return true;
}

static bool app_open_rocks(game_app *app, float fog_density) {
    const game_app_desc *d = &app->desc;
    if (d->rocks == ROCKS_OFF) return true;
    app->rock_tiles = d->rock_tiles;
    if (!app->rock_tiles) {
        app->own_rock_tiles = rocks_tileset_create(&(rocks_tileset_desc){ .jobs = app->jobs,
                                                                      .cache_path = d->rocks_cache_path });
        if (!(app->rock_tiles = app->own_rock_tiles)) return false;
    }
    app->rocks = rocks_system_create(&(rocks_system_desc){ .gfx = app->gfx, .ecs = app->ecs, .world = app->world,
                                             .tiles = app->rock_tiles, .quality = d->rocks,
                                             .fog_density = fog_density });
    if (!app->rocks) return false;
    rocks_tiles_release_meshes(app->own_rock_tiles);   /* on the GPU now; placing reads anchors */
    app_player(app)->params.obstacles_near = app_rocks_near;
    app_player(app)->params.obstacle_distance = app_rock_distance;
    app_player(app)->params.obstacle_user = app->rocks;
    app->tools.obstacle_raycast = app_rock_raycast;
    app->tools.obstacle_user = app->rocks;
    return true;
}

static bool app_open_input(game_app *app) {
    const game_app_desc *d = &app->desc;
    core_error error = { 0 };
    if (d->bindings_path && !(app->bindings = input_bindings_load(d->bindings_path, NULL, &error))) {
        core_log_error("input", "%s", error.message);
        return false;
    }
    app->input = input_system_create(&(input_system_desc){ .glfw_window = gfx_glfw_window(app->gfx), .bindings = app->bindings,
                                             .record_path = d->record_path, .replay_path = d->replay_path,
                                             .gamepad_mappings_path = d->gamepad_mappings_path }, &error);
    if (!app->input) core_log_error("input", "%s", error.message);
    app->ids.input = ecs_resource_register(app->ecs, &(ecs_resource_desc){ .name = "input", .object = app->input });
    return app->input != NULL;
}

/* ---- the world folder ------------------------------------------------------------------- */

/* The seed an old folder's world.txt records (folders from before world.db). */
static int app_world_txt_seed(const char *dir, uint64_t *seed) {
    char path[4096];
    snprintf(path, sizeof path, "%s/world.txt", dir);
    FILE *f = fopen(path, "r");
    if (!f) return 0;
    unsigned long long value;
    bool ok = fscanf(f, "seed %llu", &value) == 1;
    fclose(f);
    if (ok) *seed = value;
    return ok ? 1 : -1;
}

int game_world_dir_seed(const char *dir, uint64_t *seed) {
    /* world.db when it can be read; a damaged one is the store's to set aside, so the old
     * world.txt (if any) speaks then. */
    if (terrain_store_read_seed(dir, seed, NULL) == 1) return 1;
    return app_world_txt_seed(dir, seed);
}

/* The world folder's database: its seed checked, its edits put in the log, the player's pose
 * read back. A damaged database is reported and set aside by the store; another world's, or a
 * world another process has open, ends the start. */
static bool app_open_store(game_app *app) {
    const char *dir = app->desc.world_dir;
    uint64_t seed;
    int known = game_world_dir_seed(dir, &seed);
    if (known < 0) {
        /* Never overwritten: it may be a world someone cares about. */
        fprintf(stderr, "world: %s/world.txt does not say 'seed N'; fix or remove it\n", dir);
        return false;
    }
    if (known && seed != app->desc.seed) {
        fprintf(stderr, "world: %s holds the world of seed %llu (run with --seed %llu, or another --world)\n",
                dir, (unsigned long long)seed, (unsigned long long)seed);
        return false;
    }
    terrain_store_report report;
    core_error error = { 0 };
    app->store = terrain_store_create(&(terrain_store_desc){ .dir = dir, .edits = app->edits, .seed = app->desc.seed },
                                      &report, &error);
    if (!app->store) {
        fprintf(stderr, "world: %s%s\n", error.message,
                error.code == CORE_ERROR_MISMATCH ? " (made by another version of the generator: use another --world)"
                                                  : "");
        return false;
    }
    if (report.notice[0]) fprintf(stderr, "world: %s\n", report.notice);
    return true;
}

/* The player's pose as the world folder keeps it: text, so `sqlite3 world.db` shows it. */
#define APP_PLAYER_VALUE "game.player"

static void app_put_player(game_app *app) {
    char pose[160];
    int length = snprintf(pose, sizeof pose, "%.17g %.17g %.17g %.9g %.9g %d", app_player(app)->position[0],
                          app_player(app)->position[1], app_player(app)->position[2], (double)app_player(app)->yaw,
                          (double)app_player(app)->pitch, app_player(app)->flying ? 1 : 0);
    terrain_store_put(app->store, APP_PLAYER_VALUE, pose, (size_t)length);
}

/* Puts the player back where the last run left it (interactive play: walks and recordings
 * start where their script says). False when the folder has no pose or a bad one. */
static bool app_restore_player(game_app *app) {
    char pose[160] = "";
    int64_t size = app->store ? terrain_store_get(app->store, APP_PLAYER_VALUE, pose, sizeof pose - 1) : -1;
    if (size <= 0 || size >= (int64_t)sizeof pose) return false;
    pose[size] = '\0';
    double x, y, z, yaw, pitch;
    int flying;
    if (sscanf(pose, "%lf %lf %lf %lf %lf %d", &x, &y, &z, &yaw, &pitch, &flying) != 6 || !isfinite(x) ||
        !isfinite(y) || !isfinite(z) || !isfinite(yaw) || !isfinite(pitch)) {
        core_warn("game", "%s in the world folder reads '%s'; spawning as new", APP_PLAYER_VALUE, pose);
        return false;
    }
    app_player(app)->position[0] = x, app_player(app)->position[1] = y, app_player(app)->position[2] = z;
    app_player(app)->yaw = (float)yaw, app_player(app)->pitch = (float)pitch;
    app_player(app)->flying = flying != 0;
    return true;
}

/* An autosave: a snapshot now, written on the store's thread (a save still in flight: next
 * frame). The last save waits for the disk. */
static void app_save(game_app *app, bool last) {
    if (!app->store) return;
    TRACE_ZONE("game.save");
    if (app->spawned) app_put_player(app);
    core_error error = { 0 };
    if (last) {
        if (!terrain_store_save(app->store, &error))
            fprintf(stderr, "world: the last save failed: %s\n", error.message);
    } else if (terrain_store_save_async(app->store)) app->last_save_ns = core_time_ns();
}

static bool app_open_terrain(game_app *app) {
    terrain_generation_desc params = terrain_generation_defaults(app->desc.seed);
    /* Always a log: an edited chunk can then leave the cache like any other and come back as
     * edited. With a world folder it is also loaded and saved. */
    app->edits = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = terrain_generation_key(&params) });
    if (app->desc.world_dir && !app_open_store(app)) return false;
    if (app->desc.cliffs != ROCKS_OFF && !(app->cliffs = rocks_cliffs_create(&(rocks_cliffs_desc){
                                            .seed = app->desc.seed, .jobs = app->jobs,
                                            .cache_dir = app->desc.cliffs_cache_dir })))
        return false;
    float reach[3];   /* an edit meshes again the chunks whose blocks it can change */
    rocks_cliffs_reach(app->cliffs, reach);
    app->world = terrain_world_create(&(terrain_world_desc){ .generation = params, .generate = app->desc.generate,
                                                             .generate_user = app->desc.generate_user,
                                                             .edits = app->edits,
                                                             .amplify = app->cliffs ? rocks_cliffs_amplify : NULL,
                                                             .amplify_user = app->cliffs,
                                                             .amplify_reach = { reach[0], reach[1], reach[2] } });
    app->ecs = ecs_world_create(&(ecs_world_desc){ .jobs = app->jobs });
    app->terrain = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = app->ecs, .terrain = app->world });
    int iterations = app->desc.stabilize_iterations;
    if (iterations <= 0 && !app->interactive) iterations = APP_REPLAY_STABILIZE_ITERATIONS;
    if (iterations > 0)
        terrain_ecs_set_editing(app->terrain, &(terrain_editing_desc){ .stabilize = { .max_iterations = iterations } });
    terrain_stream_desc stream = app->desc.stream;
    if (app->desc.pixel_error > 0 && stream.half_width <= 0 && stream.levels <= 0) {
        stream.pixel_error = app->desc.pixel_error;
        stream.viewport_height = app->desc.height;   /* the view's fov: app_screen_changed */
    }
    terrain_ecs_stream(app->terrain, &stream);
    app_create_entities(app);
    return true;
}

/* ---- pictures along a walk (`shot` waypoints) ------------------------------------------- */

#define APP_SHOT_MIN_FRAMES 8              /* frames held before a picture: the turn drawn */
#define APP_SHOT_MAX_FRAMES 120            /* the most a picture waits for streaming to settle */

/* The first held frame: face the most open view, and look down as much as the height above the
 * ground asks (about the ground 400 m ahead, between 0.1 and 0.3 rad, so the sky stays in the
 * picture). */
static void app_frame_shot(game_app *app) {
    game_player *pl = app_player(app);
    const game_walk_point *point = &app->walk.points[app->walker.index - 1];   /* the one reached */
    if (point->has_look_at) {              /* a point to keep in the middle (a pile of rocks) */
        double eye[3];
        game_player_eye(pl, eye);
        double dx = point->look_at[0] - eye[0], dy = point->look_at[1] - eye[1], dz = point->look_at[2] - eye[2];
        if (hypot(dx, dz) > 0.5) {         /* forward is (sin yaw, −cos yaw) (player.h) */
            pl->yaw = (float)atan2(dx, -dz);
            pl->pitch = (float)atan2(dy, hypot(dx, dz));
            return;
        }
    }
    if (point->has_look) {                 /* the walk says where to look (a cave's mouth) */
        pl->yaw = (float)remainder(APP_PI + point->look_yaw * (APP_PI / 180.0), 2.0 * APP_PI);
        pl->pitch = (float)(point->look_pitch * (APP_PI / 180.0));
        return;
    }
    pl->yaw = game_player_open_yaw(pl, app->world, pl->yaw, NULL);
    double eye[3];
    game_player_eye(pl, eye);
    float ground = terrain_world_top(app->world, eye[0], eye[2]);
    double above = fmax(eye[1] - (double)ground, 0.0);
    pl->pitch = -(float)fmin(fmax(atan2(above, 400.0), 0.1), 0.3);
}

/* Held long enough, and every chunk the rings want is in (or the wait is over). */
static bool app_shot_ready(game_app *app) {
    if (app->shot_hold < APP_SHOT_MIN_FRAMES) return false;
    terrain_ecs_stream_stats_info s = terrain_ecs_stream_stats(app->terrain);
    return s.mesh_chunks_ready == s.mesh_chunks_wanted || app->shot_hold >= APP_SHOT_MAX_FRAMES;
}

/* "out/play.png" → "out/play-3.png". */
static void app_shot_path(const char *sheet, int number, char *out, size_t size) {
    const char *dot = strrchr(sheet, '.'), *slash = strrchr(sheet, '/');
    int stem = dot && (!slash || dot > slash) ? (int)(dot - sheet) : (int)strlen(sheet);
    snprintf(out, size, "%.*s-%d%s", stem, sheet, number, dot && (!slash || dot > slash) ? dot : ".png");
}

/* The drawn frame: written as FILE-N.png beside --screenshot FILE, and kept at half size. */
static void app_take_shot(game_app *app) {
    int width, height;
    gfx_size(app->gfx, &width, &height);
    size_t size = (size_t)width * (size_t)height * 4;
    uint8_t *rgba = core_alloc(size);
    gfx_read_pixels(app->gfx, rgba);
    for (size_t i = 3; i < size; i += 4) rgba[i] = 255;   /* no meaningful alpha */
    int number = app->shot_count + 1;
    char path[4096] = "";
    if (app->desc.screenshot_path) {
        app_shot_path(app->desc.screenshot_path, number, path, sizeof path);
        if (!gfx_write_png(path, width, height, rgba)) path[0] = '\0';
    }
    int hw = width / 2, hh = height / 2;
    uint8_t *half = core_alloc((size_t)hw * (size_t)hh * 4);
    for (int y = 0; y < hh; y++)
        for (int x = 0; x < hw; x++)
            for (int c = 0; c < 4; c++) {
                const uint8_t *q = rgba + ((size_t)(2 * y) * (size_t)width + (size_t)(2 * x)) * 4 + c;
                half[((size_t)y * (size_t)hw + (size_t)x) * 4 + c] =
                    (uint8_t)((q[0] + q[4] + q[(size_t)width * 4] + q[(size_t)width * 4 + 4] + 2) / 4);
            }
    core_free(rgba, size);
    app->shots = core_grow(app->shots, &app->shot_capacity, (size_t)app->shot_count + 1, sizeof *app->shots);
    app->shots[app->shot_count++] = (struct app_shot){ half, hw, hh };
    printf("world: picture %d at (%.0f, %.0f, %.0f)%s%s\n", number, app_player(app)->position[0], app_player(app)->position[1],
           app_player(app)->position[2], path[0] ? " -> " : "", path);
    fflush(stdout);
}

/* The pictures side by side (two columns, up to four; three beyond), at half size, in cells of
 * the first picture's size (a window resized meanwhile: the others are cropped or padded). */
static bool app_write_contact_sheet(game_app *app, const char *path) {
    int hw = app->shots[0].width, hh = app->shots[0].height, columns = app->shot_count <= 4 ? 2 : 3;
    if (app->shot_count == 1) columns = 1;
    int rows = (app->shot_count + columns - 1) / columns;
    int sheet_w = columns * hw, sheet_h = rows * hh;
    size_t size = (size_t)sheet_w * (size_t)sheet_h * 4;
    uint8_t *sheet = core_alloc(size);
    for (size_t i = 0; i < size; i += 4) memcpy(sheet + i, (const uint8_t[4]){ 24, 26, 30, 255 }, 4);
    /* A last row that is not full is centred, so the sheet reads as laid out, not as a gap. */
    int last_row = (app->shot_count - 1) / columns, in_last_row = app->shot_count - last_row * columns;
    for (int n = 0; n < app->shot_count; n++) {
        const struct app_shot *shot = &app->shots[n];
        int w = shot->width < hw ? shot->width : hw, h = shot->height < hh ? shot->height : hh;
        int row = n / columns, x0 = n % columns * hw + (row == last_row ? (columns - in_last_row) * hw / 2 : 0);
        for (int y = 0; y < h; y++)
            memcpy(sheet + (((size_t)(row * hh + y)) * (size_t)sheet_w + (size_t)x0) * 4,
                   shot->rgba + (size_t)y * (size_t)shot->width * 4, (size_t)w * 4);
    }
    bool ok = gfx_write_png(path, sheet_w, sheet_h, sheet);
    core_free(sheet, size);
    if (ok) printf("world: %d pictures side by side -> %s\n", app->shot_count, path);
    return ok;
}

static void app_free_shots(game_app *app) {
    for (int n = 0; n < app->shot_count; n++)
        core_free(app->shots[n].rgba, (size_t)app->shots[n].width * (size_t)app->shots[n].height * 4);
    core_free(app->shots, app->shot_capacity * sizeof *app->shots);
}

/* The eye at desc.at, standing where that keeps it there. Flying where standing would move it:
 * the eye in the ground (the controller pushes a walker out) or nothing within a step below the
 * feet (it would fall). */
static void app_place_at(game_app *app) {
    const double *at = app->desc.at;
    game_player *pl = app_player(app);
    double feet = at[1] - (double)pl->params.eye_height;
    pl->position[0] = at[0], pl->position[1] = feet, pl->position[2] = at[2];
    memset(pl->velocity, 0, sizeof pl->velocity);
    pl->crouching = pl->on_ground = false;
    pl->flying = terrain_field_at(app->world, at[0], at[1], at[2], 0) >= 0 ||
                 terrain_field_at(app->world, at[0], feet - (double)pl->params.step_height, at[2], 0) < 0;
}

static void app_spawn_player(game_app *app) {
    const game_app_desc *d = &app->desc;
    game_player_desc params = { 0 };
    if (app->interactive) {
        params.region_ready = app_region_ready;
        params.region_user = app;
    }
    game_player *pl = app_player(app);
    game_player_init(pl, &params);
    if (d->at_set) app_place_at(app);          /* no spawn search: the default view from there */
    else game_player_spawn(pl, app->world, d->spawn[0], d->spawn[1]);
    pl->yaw = 3.14159265f;                     /* towards +z: the slopes in view face the sun */
    pl->pitch = GAME_WALKER_PITCH;
    /* A first view of the land, not of a hillside. Scripted walks keep +z: their paths and the
     * benchmarks were laid out along it. */
    if (app->interactive || d->face_open_view) pl->yaw = game_player_open_yaw(pl, app->world, pl->yaw, NULL);
    /* --at and --look win over the saved pose, each over its own part of it. */
    if (app->interactive && app_restore_player(app) && d->at_set) app_place_at(app);
    if (d->look_set) {
        pl->yaw = (float)remainder(APP_PI + d->look[0] * (APP_PI / 180.0), 2.0 * APP_PI);
        pl->pitch = (float)(d->look[1] * (APP_PI / 180.0));
    }
    app_player_placed(app);
    app->holding = d->at_set || d->look_set;
    app->spawned = true;
}

/* terrain_view's yaw and pitch as --look takes them (app.h): degrees, yaw in [0, 360). */
static void app_look_degrees(float yaw, float pitch, double look[2]) {
    look[0] = fmod((double)yaw * (180.0 / APP_PI) - 180.0, 360.0);
    if (look[0] < 0) look[0] += 360.0;
    look[1] = (double)pitch * (180.0 / APP_PI);
}

/* The far terrain's levels without a pixel-error target (all 0 with one: derived from it).
 * 96² cells a level: each level's nearest vertices are then (96/4 − 2) of its spacings from the
 * camera, where its mean height error (spacing/4, terrain_clipmap_spacing_error) spans 1/88 of
 * a radian, 7 px at 720 lines and 60°: about what the finest level has where the rings end
 * (2 m at 192 m, 6.5 px), which no finer level elsewhere makes up for. 128 cells drew the
 * coarser levels at 5.2 px for 60 % more triangles (the world walk at 230 m: 47 k against 29 k
 * a frame; the pictures differ by less than 1 of 255 per pixel on average). The finest level
 * is twice the outermost ring's cells (8 m for 3 levels): the rings' square, the clipmap's
 * hole, would hold a level of their own spacing whole, all pit (level_buried). Five levels
 * reach 5.8 km, where the 6 km far plane's own fade has begun, and the pit's wall keeps the
 * band the 4 m levels gave it (8 m: one cell of the level that draws it). */
typedef struct app_clipmap_levels {
    int cells, levels;
    float finest_spacing, hole_band;
} app_clipmap_levels;

static app_clipmap_levels app_fixed_clipmap_levels(float outermost_cells, float pixel_error) {
    if (pixel_error > 0.0f) return (app_clipmap_levels){ 0 };
    return (app_clipmap_levels){ .cells = 96, .levels = 5, .finest_spacing = 2.0f * outermost_cells,
                                 .hole_band = 2.0f * outermost_cells };
}

game_app *game_app_create(const game_app_desc *desc) {
    game_app *app = core_calloc(1, sizeof *app);
    app->desc = *desc;
    game_app_desc *d = &app->desc;
    if (d->walk) {                         /* a copy: resolving `cave` lines rewrites points */
        game_walk_copy(d->walk, &app->walk);
        d->walk = &app->walk;
    }
    if (!d->width || !d->height) d->width = 1280, d->height = 720;
    if (!(d->max_loading_seconds > 0)) d->max_loading_seconds = 300.0;
    if (!(d->step_seconds > 0)) d->step_seconds = 1.0f / 60.0f;
    app->gfx = gfx_context_create(&(gfx_context_desc){ .width = d->width, .height = d->height, .title = "world (loading)",
                                       .headless = d->headless });
    if (!app->gfx) goto fail;
    app->windowed = gfx_backend_get(app->gfx) == GFX_BACKEND_WINDOW;
    app->interactive = !d->walk && !d->record_path && !d->replay_path;
    /* Offscreen nobody can close the window: something has to end the run. */
    if (!app->windowed && !d->frames && !d->walk && !d->replay_path) d->frames = 300;
    app->jobs = job_system_create(&(job_system_desc){ .threads = d->threads });
    if (!app_open_terrain(app)) goto fail;
    /* Thin fog: the clipmap shows ground out to several kilometres. */
    float fog_density = d->no_clipmap ? 0 : 0.0005f;
    app->renderer = terrain_renderer_create(app->gfx, &(terrain_renderer_desc){
        .sea_level = terrain_world_generation(app->world)->sea_level, .fog_density = fog_density,
        .no_occlusion = d->no_occlusion, .detail_distance = d->no_terrain_detail ? -1.0f : 0.0f,
        .shadows = d->shadows, .sky_apart = true });
    if (!app->renderer || !app_open_input(app) || !(app->hud = gfx_text_create(app->gfx))) goto fail;
    if (!d->no_clipmap) {
        terrain_stream_desc rings = terrain_ecs_stream_desc(app->terrain);
        /* The stacks' surface where chunks are cached, sampled as the outermost ring meshes it,
         * and snapped as the rings are: the far terrain meets the chunks along their hole's
         * border and shows edits from afar (002 §3.5). Without --pixel-error the levels are
         * fixed (app_fixed_clipmap_levels). */
        float outermost = (float)(1 << (rings.levels - 1));
        app_clipmap_levels fixed = app_fixed_clipmap_levels(outermost, d->pixel_error);
        app->clipmap = terrain_clipmap_create(&(terrain_clipmap_desc){
            .cells = fixed.cells, .finest_spacing = fixed.finest_spacing, .levels = fixed.levels,
            .hole_band = fixed.hole_band,
            .generation = *terrain_world_generation(app->world), .jobs = app->jobs,
            .world = app->world, .mesh_step = outermost, .centre_snap = TERRAIN_MESH_CELLS * outermost,
            .pixel_error = d->pixel_error, .viewport_height = d->height,
            .inner_distance = (float)terrain_rings_clearance(rings.half_width, rings.levels, rings.levels - 1) });
        terrain_ecs_set_clipmap(app->terrain, app->clipmap);
        terrain_renderer_set_clipmap(app->renderer, app->clipmap);
        app_view(app)->far_distance = 6000.0f;
    }
    if (d->grass != GRASS_OFF &&
        !(app->grass = grass_system_create(&(grass_system_desc){ .gfx = app->gfx, .ecs = app->ecs, .world = app->world,
                                                   .quality = d->grass, .fog_density = fog_density })))
        goto fail;
    if (d->water != TERRAIN_WATER_OFF &&
        !(app->water = terrain_water_create(&(terrain_water_desc){ .gfx = app->gfx, .ecs = app->ecs, .world = app->world,
                                                                   .quality = d->water, .fog_density = fog_density })))
        goto fail;
    app_spawn_player(app);
    game_tools_init(&app->tools);
    if (!app_open_rocks(app, fog_density)) goto fail;
    app_add_systems(app);
    app->loading = app->running = true;
    app->start_ns = app->last_ns = app->last_save_ns = core_time_ns();
    if (d->setup) d->setup(app, app->ecs, d->setup_user);
    return app;
fail:
    game_app_destroy(app);
    return NULL;
}

void game_app_destroy(game_app *app) {
    if (!app) return;
    input_system_destroy(app->input);
    input_bindings_destroy(app->bindings);
    gfx_text_destroy(app->hud);
    if (app->store) app_save(app, true);
    terrain_store_destroy(app->store);
    grass_system_destroy(app->grass);               /* its patches live on the terrain's entities */
    rocks_system_destroy(app->rocks);               /* so do its RockTiles */
    terrain_water_destroy(app->water);
    if (app->terrain) terrain_ecs_destroy(app->terrain);
    terrain_clipmap_destroy(app->clipmap);
    terrain_renderer_destroy(app->renderer);
    ecs_world_destroy(app->ecs);
    terrain_world_destroy(app->world);
    rocks_cliffs_destroy(app->cliffs);       /* after the world: its hook reads them */
    terrain_edit_log_destroy(app->edits);
    rocks_tileset_destroy(app->own_rock_tiles);
    job_system_destroy(app->jobs);
    app_free_shots(app);
    game_walk_free(&app->walk);
    gfx_context_destroy(app->gfx);
    core_free(app->cpu_ms, app->cpu_capacity * sizeof *app->cpu_ms);
    core_free(app->engine_ms, app->engine_capacity * sizeof *app->engine_ms);
    core_free(app->thread_ms, app->thread_capacity * sizeof *app->thread_ms);
    core_free(app->triangles, app->triangles_capacity * sizeof *app->triangles);
    core_free(app, sizeof *app);
}

/* ---- one frame ---------------------------------------------------------------------------- */

/* The start area is in: every chunk the rings want around the spawn is meshed (or known empty)
 * and the player's collision chunks are generated. */
static bool app_loaded(game_app *app) {
    terrain_ecs_stream_stats_info s = terrain_ecs_stream_stats(app->terrain);
    double feet[3] = { app_player(app)->position[0], app_player(app)->position[1], app_player(app)->position[2] };
    double lo[3] = { feet[0] - 8, feet[1] - 8, feet[2] - 8 }, hi[3] = { feet[0] + 8, feet[1] + 8, feet[2] + 8 };
    bool ready = s.mesh_chunks_wanted > 0 && s.mesh_chunks_ready == s.mesh_chunks_wanted &&
                 terrain_ecs_region_ready(app->terrain, lo, hi);
    double waited = (double)(core_time_ns() - app->start_ns) * 1e-9;
    if (!ready && waited >= app->desc.max_loading_seconds) {
        core_warn("game", "start area not ready after %.0f s (%d of %d chunks): starting anyway", waited,
                  s.mesh_chunks_ready, s.mesh_chunks_wanted);
        return true;
    }
    return ready;
}

/* The HUD's text scale: 2 at 720 rows (what it was drawn for), in proportion elsewhere. */
static float app_hud_scale(int height) { return fmaxf(1.0f, floorf((float)height / 360.0f + 0.5f)); }

#define APP_HUD_LINES 4
#define APP_HINT_SECONDS 6.0               /* the controls' hint shows this long, then fades */
#define APP_HINT_FADE 1.5
#define APP_NOTE_SECONDS 4.0               /* a note (where F12's picture went) shows this long */
#define APP_SCREENSHOT_FOLDER "screenshots"
static const char app_hint[] = "WASD move   mouse look   Space jump   Shift sprint   F fly   "
                               "mouse buttons use the tool   Tab next tool   F1 HUD   Esc quit";

/* The controls, along the bottom for the first seconds of a run in a window, then faded out. */
static void app_draw_hint(game_app *app, int width, int height, float scale) {
    if (!app->windowed || !app->interactive || app->loading) return;
    double shown = (double)(app->last_ns - app->play_start_ns) * 1e-9;
    float alpha = (float)fmin(1.0, fmax(0.0, (APP_HINT_SECONDS + APP_HINT_FADE - shown) / APP_HINT_FADE));
    if (alpha <= 0.0f) return;
    while (scale > 1.0f && gfx_text_width(app_hint, scale) > 0.9f * (float)width) scale -= 1.0f;
    float text_width = gfx_text_width(app_hint, scale);
    if (text_width > 0.95f * (float)width) return;       /* too small a window for it */
    const float colour[4] = { 1, 1, 1, alpha };
    gfx_text_print(app->hud, 0.5f * ((float)width - text_width), (float)height - 20.0f * scale, scale, colour, "%s",
                   app_hint);
}

/* The passing note (where a screenshot went), above the hint's line, then faded out. */
static void app_draw_note(game_app *app, int width, int height, float scale) {
    if (!app->hud_note[0]) return;
    double shown = (double)(core_time_ns() - app->hud_note_ns) * 1e-9;
    float alpha = (float)fmin(1.0, fmax(0.0, (APP_NOTE_SECONDS + APP_HINT_FADE - shown) / APP_HINT_FADE));
    if (alpha <= 0.0f) {
        app->hud_note[0] = '\0';
        return;
    }
    while (scale > 1.0f && gfx_text_width(app->hud_note, scale) > 0.9f * (float)width) scale -= 1.0f;
    float text_width = gfx_text_width(app->hud_note, scale);
    const float colour[4] = { 1, 1, 0.6f, alpha };
    gfx_text_print(app->hud, fmaxf(0.0f, 0.5f * ((float)width - text_width)), (float)height - 34.0f * scale, scale,
                   colour, "%s", app->hud_note);
}

/* Frame rate, streaming, position and the tool, in the top-left corner: at most half the width
 * and a quarter of the height, shrunk or cut to fit (a tiny window shows none). F1 hides it. */
static void app_draw_hud(game_app *app) {
    if (app->desc.no_hud || app->walker.shot_due) return;   /* pictures show the world alone */
    int width, height;
    gfx_size(app->gfx, &width, &height);
    float scale = app_hud_scale(height);
    app_draw_hint(app, width, height, scale);
    app_draw_note(app, width, height, scale);
    if (app->hud_hidden) {
        gfx_text_draw(app->hud);
        return;
    }
    terrain_ecs_stream_stats_info s = terrain_ecs_stream_stats(app->terrain);
    double seconds = app->frame_seconds;
    char lines[APP_HUD_LINES][160];
    int count = 0;
    snprintf(lines[count++], sizeof lines[0], "%.0f fps  %.1f ms%s", seconds > 0 ? 1.0 / seconds : 0.0,
             seconds * 1e3, app->loading ? "  loading" : "");
    snprintf(lines[count++], sizeof lines[0], "chunks %d resident, %d pending, %d jobs, %.0f MB",
             s.mesh_chunks_ready + s.mesh_chunks_kept, s.mesh_chunks_wanted - s.mesh_chunks_ready, s.jobs_in_flight,
             (double)s.resident_bytes / (1024.0 * 1024.0));
    double look[2];
    app_look_degrees(app_view(app)->yaw, app_view(app)->pitch, look);   /* as --at and --look take them */
    const game_player *pl = app_player(app);
    snprintf(lines[count++], sizeof lines[0], "x %.1f y %.1f z %.1f  yaw %.0f pitch %.0f  seed %llu%s",
             app_view(app)->camera[0], app_view(app)->camera[1], app_view(app)->camera[2], look[0], look[1],
             (unsigned long long)app->desc.seed, pl->swimming ? "  swimming" : pl->in_water && !pl->flying ? "  wading" : "");
    if (app->interactive) snprintf(lines[count++], sizeof lines[0], "%s", game_tools_hint(&app->tools));
    /* Shrink to the corner: a smaller scale, then fewer lines. */
    for (; count > 0; count--) {
        float widest = 0;
        for (int n = 0; n < count; n++) widest = fmaxf(widest, gfx_text_width(lines[n], 1.0f));
        while (scale > 1.0f && widest * scale > 0.5f * (float)width) scale -= 1.0f;
        if (widest * scale <= 0.5f * (float)width && 11.0f * scale * (float)count <= 0.25f * (float)height) break;
    }
    float line_height = 11.0f * scale;
    const float white[4] = { 1, 1, 1, 1 }, aim[4] = { 1, 1, 0.6f, 1 }, idle[4] = { 0.7f, 0.7f, 0.7f, 1 };
    for (int n = 0; n < count; n++) {
        const float *colour = app->interactive && n == 3 ? (app->tools.aimed ? aim : idle) : white;
        gfx_text_print(app->hud, 4.0f * scale, 4.0f * scale + line_height * (float)n, scale, colour, "%s", lines[n]);
    }
    gfx_text_draw(app->hud);
}

/* F12: a new dated file in screenshots/, never over another (game/screenshot.h); the HUD says
 * where it went, or that it failed. */
static void app_take_screenshot(game_app *app) {
    char path[256];
    time_t now = time(NULL);
    struct tm local;
    localtime_r(&now, &local);
    bool ok = game_screenshot_reserve(APP_SCREENSHOT_FOLDER, "world", &local, path, sizeof path);
    if (ok && !gfx_screenshot(app->gfx, path)) {
        unlink(path); /* our own empty file: nothing else was there */
        ok = false;
    }
    if (ok) snprintf(app->hud_note, sizeof app->hud_note, "screenshot: %s", path);
    else snprintf(app->hud_note, sizeof app->hud_note, "screenshot failed (see the log)");
    app->hud_note_ns = core_time_ns();
}

/* Input that moves the player or turns the view (tools, pictures and the HUD do not). */
static bool app_moves(const input_actions *a) {
    uint32_t moving = INPUT_ACTION_BIT(INPUT_ACTION_JUMP) | INPUT_ACTION_BIT(INPUT_ACTION_CROUCH) |
                      INPUT_ACTION_BIT(INPUT_ACTION_TOGGLE_FLY);
    return a->move_x || a->move_y || a->look_x || a->look_y || ((a->down | a->pressed) & moving);
}

/* CPU time the calling thread has used: a frame's work on the main thread, without the time it
 * spent blocked (a driver waiting for its rasteriser, a lock). */
static uint64_t app_thread_cpu_ns(void) {
    struct timespec t;
    if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t) != 0) return 0;
    return (uint64_t)t.tv_sec * 1000000000ull + (uint64_t)t.tv_nsec;
}

static void app_record_cpu(game_app *app, double cpu_ms, double engine_ms, double thread_ms, double triangles) {
    app->triangles = core_grow(app->triangles, &app->triangles_capacity, app->cpu_count + 1, sizeof *app->triangles);
    app->triangles[app->cpu_count] = triangles;
    app->cpu_ms = core_grow(app->cpu_ms, &app->cpu_capacity, app->cpu_count + 1, sizeof *app->cpu_ms);
    app->engine_ms = core_grow(app->engine_ms, &app->engine_capacity, app->cpu_count + 1, sizeof *app->engine_ms);
    app->thread_ms = core_grow(app->thread_ms, &app->thread_capacity, app->cpu_count + 1, sizeof *app->thread_ms);
    app->engine_ms[app->cpu_count] = engine_ms;
    app->thread_ms[app->cpu_count] = thread_ms;
    app->cpu_ms[app->cpu_count++] = cpu_ms;
}

static bool app_last_frame(const game_app *app) {
    if (app->loading) return false;
    if (app->desc.frames && app->frames + 1 >= app->desc.frames) return true;
    return app->desc.walk && game_walker_done(&app->walker);
}

static void app_finish_loading(game_app *app) {
    app->loading = false;
    app->play_start_ns = core_time_ns();
    if (app->desc.walk) {
        game_walk_found found = game_walk_resolve_stops(&app->walk, app->world, app_player(app));
        if (found.caves)
            printf("world: %d look%s into a cave or under an arch on the walk\n", found.caves, found.caves == 1 ? "" : "s");
        if (found.shores)
            printf("world: %d look%s over water from a shore on the walk\n", found.shores, found.shores == 1 ? "" : "s");
        if (found.rocks)
            printf("world: %d look%s at a pile of rocks on the walk\n", found.rocks, found.rocks == 1 ? "" : "s");
        if (found.cliffs)
            printf("world: %d look%s at a cliff on the walk\n", found.cliffs, found.cliffs == 1 ? "" : "s");
        game_walker_start(&app->walker, app->desc.walk, app_player(app));
        app_player_placed(app);
    }
    gfx_window_set_title(app->gfx, "world");
}

/* The frame's memory by what holds it, as counters (the trace's "memory.bytes" is the whole
 * process's heap): terrain stacks, meshes made and uploaded, rocks, grass, the trace itself. */
static void app_memory_counters(game_app *app) {
    if (!trace_active()) return;
    terrain_ecs_stream_stats_info st = terrain_ecs_stream_stats(app->terrain);
    trace_counter("memory.terrain_stacks", (double)st.stacks_bytes);
    trace_counter("memory.meshes_cpu", (double)st.cpu_mesh_bytes);
    trace_counter("memory.meshes_gpu", (double)st.gpu_mesh_bytes);
    if (app->rocks) {
        rocks_system_stats_info r = rocks_system_stats(app->rocks);
        trace_counter("memory.rocks", (double)(r.tiles_bytes + r.placed_bytes + r.draw_bytes + r.gpu_bytes));
    }
    if (app->grass) trace_counter("memory.grass", (double)grass_system_stats(app->grass).bytes);
}

/* ---- the frame's systems (app.h, THE FRAME IS ONE ecs_progress) -------------------------- */

#define APP_MAX_FRAME_SECONDS 0.25f        /* a longer frame steps this much (a stall, a debugger) */

/* The box the player can reach within `seconds`, streamed in: scripted, recorded and replayed
 * runs read input and step only then (app.h, ONE PATH). The bound is the controller's own
 * (player.c) at the fastest it can go: a sprint in flight or in water, a frame of gravity, a
 * step and the capsule. */
static bool app_reach_ready(game_app *app, const game_player *pl, float seconds) {
    const game_player_desc *p = &pl->params;
    float v = sqrtf(pl->velocity[0] * pl->velocity[0] + pl->velocity[1] * pl->velocity[1] +
                    pl->velocity[2] * pl->velocity[2]);
    float speed = v + fmaxf(p->fly_sprint_speed, p->swim_sprint_speed + p->dive_speed) + p->gravity * seconds;
    float reach = speed * seconds + p->step_height + p->radius + 2.0f;
    double min[3], max[3];
    for (int i = 0; i < 3; i++) {
        min[i] = floor(pl->position[i] - (double)reach);
        max[i] = ceil(pl->position[i] + (double)reach + (i == 1 ? (double)p->height : 0.0));
    }
    return terrain_ecs_region_ready(app->terrain, min, max);
}

/* input: devices, a recording or its replay → the GameActions resource; and the keys the app
 * answers itself (quit, F1, F11, F12). */
static void app_input_system(ecs_iter *it) {
    game_app *app = it->user;
    GameActions *out = ecs_resource_get(it->world, app->ids.actions);
    *out = (GameActions){ .dt = it->dt };
    /* While loading, and while a scripted or recorded run waits for streaming, a recording
     * neither records nor replays: frame N of a recording must be frame N of its replay. */
    bool read = app->interactive ||
                (!app->loading && app_reach_ready(app, app_player(app), APP_MAX_FRAME_SECONDS));
    if (read) {
        if (!input_update(app->input, it->dt)) {
            app->running = false;
            return;
        }
        out->actions = *input_actions_get(app->input);
        out->dt = input_frame_dt(app->input);
        out->read = true;
    }
    uint32_t pressed = out->actions.pressed;
    if ((pressed & INPUT_ACTION_BIT(INPUT_ACTION_QUIT)) || gfx_window_should_close(app->gfx)) app->running = false;
    app->screenshot_wanted = (pressed & INPUT_ACTION_BIT(INPUT_ACTION_SCREENSHOT)) != 0;
    if (pressed & INPUT_ACTION_BIT(INPUT_ACTION_FULLSCREEN)) gfx_window_toggle_fullscreen(app->gfx);
    if (pressed & INPUT_ACTION_BIT(INPUT_ACTION_TOGGLE_HUD)) app->hud_hidden = !app->hud_hidden;
}

/* The frame's input as one fixed step sees it: held keys and sticks in every step, presses and
 * the view's turn in the first only (they happened once). */
static input_actions app_step_actions(const input_actions *frame, bool first) {
    input_actions a = *frame;
    if (!first) {
        a.pressed = a.released = 0;
        a.look_x = a.look_y = 0.0f;
    }
    return a;
}

/* One fixed step of a body. The player's: the walk script or the frame's input; others: none. */
static void app_player_step(game_app *app, GamePlayer *player, const input_actions *frame, bool first,
                            bool controlled) {
    static const input_actions none = { 0 };
    game_player *pl = &player->body;
    memcpy(player->previous, pl->position, sizeof player->previous);
    input_actions actions = controlled ? app_step_actions(frame, first) : none;
    if (controlled && app->desc.walk) actions = game_walker_step(&app->walker, pl, GAME_PLAYER_STEP);
    /* A view asked for stays exactly so until the first move: the controller would push an eye
     * out of the ground, let the feet settle or clamp the pitch to its own limit. */
    if (controlled) app->holding = app->holding && !app_moves(&actions);
    if (!(controlled && app->holding)) game_player_update(pl, app->world, &actions, GAME_PLAYER_STEP);
}

/* The walk holds the player still: for a picture, or done. */
static bool app_walk_stands(const game_app *app) {
    return app->desc.walk && (app->walker.shot_due || game_walker_done(&app->walker));
}

/* player: bodies in fixed steps of GAME_PLAYER_STEP over the frame's time. The simulation holds
 * (no step, no time banked) while loading, while a scripted or recorded run waits for
 * streaming, and while a walk stands still for a picture. */
static void app_player_system(ecs_iter *it) {
    game_app *app = it->user;
    const GameActions *in = ecs_resource_get(it->world, app->ids.actions);
    GameClock *clock = ecs_resource_get(it->world, app->ids.clock);
    if (app->loading) return;
    bool held = (!in->read && !app->interactive) || app->walker.shot_due;
    bool waited = !in->read && !app->interactive;
    clock->banked = held ? 0.0 : clock->banked + (double)fminf(in->dt, APP_MAX_FRAME_SECONDS);
    int steps = 0;
    for (; clock->banked >= (double)GAME_PLAYER_STEP; steps++) clock->banked -= (double)GAME_PLAYER_STEP;
    while (ecs_query_next(it)) {
        GamePlayer *players = ecs_field(it, 0);
        for (int i = 0; i < it->count; i++) {
            bool controlled = it->entities[i] == app->player_entity;
            /* A walk ends on the step that finishes it, whatever the frame has left. */
            for (int step = 0; step < steps && !(controlled && app_walk_stands(app)); step++)
                app_player_step(app, &players[i], &in->actions, step == 0, controlled);
            waited = waited || (controlled && players[i].body.waiting);
        }
    }
    app->waiting += waited;
    clock->steps += (uint64_t)steps;
    clock->seconds = (double)clock->steps * (double)GAME_PLAYER_STEP;
    clock->alpha = held ? 1.0f : (float)(clock->banked / (double)GAME_PLAYER_STEP);
}

/* A camera at its body's eye, between the last two steps by `alpha`, less the head bob. */
static void app_camera_follow(game_app *app, GameCamera *camera, const GamePlayer *player, float alpha) {
    const game_player *pl = &player->body;
    terrain_view *view = &camera->view;
    game_player_eye(pl, view->camera);
    for (int i = 0; i < 3; i++)
        view->camera[i] -= (1.0 - (double)alpha) * (pl->position[i] - player->previous[i]);
    if (!app->desc.no_head_bob) view->camera[1] -= game_player_bob(pl);
    view->yaw = pl->yaw;
    view->pitch = pl->pitch;
}

/* Whether the eye is in the ground; false over ground not streamed in yet (reading it would
 * generate it here, on the main thread). */
static bool app_eye_in_ground(const game_app *app, const terrain_view *view) {
    double lo[3], hi[3];
    for (int i = 0; i < 3; i++) lo[i] = floor(view->camera[i]) - 1.0, hi[i] = ceil(view->camera[i]) + 1.0;
    return terrain_ecs_region_ready(app->terrain, lo, hi) &&
           terrain_field_at(app->world, view->camera[0], view->camera[1], view->camera[2], 0) >= 0;
}

/* A camera at its body, `alpha` of the way from the last step to this one. The straight line
 * between two steps can cut a corner the body went round (a step up, a push out of a wall):
 * then the view is drawn from this step itself. True when even that eye is in the ground. */
static bool app_camera_place(game_app *app, GameCamera *camera, const GamePlayer *body, float alpha) {
    app_camera_follow(app, camera, body, alpha);
    if (!app_eye_in_ground(app, &camera->view)) return false;
    if (alpha >= 1.0f) return true;
    app_camera_follow(app, camera, body, 1.0f);
    return app_eye_in_ground(app, &camera->view);
}

/* camera: every camera's view; streaming follows those tagged GameStreamViewer, culling and
 * drawing the app's own. */
static void app_camera_system(ecs_iter *it) {
    game_app *app = it->user;
    const GameClock *clock = ecs_resource_get(it->world, app->ids.clock);
    int width, height;
    gfx_size(app->gfx, &width, &height);
    float time = app->windowed ? (float)((double)(app->last_ns - app->start_ns) * 1e-9)
                               : (float)(app->frames + app->loading_frames) * app->desc.step_seconds;
    double eyes[TERRAIN_MAX_VIEWERS][3];
    int viewers = 0;
    while (ecs_query_next(it)) {
        GameCamera *cameras = ecs_field(it, 0);
        bool streams = ecs_field_is_set(it, 1);
        for (int i = 0; i < it->count; i++) {
            GameCamera *c = &cameras[i];
            const GamePlayer *followed = c->follows ? ecs_get(it->world, c->follows, app->ids.player) : NULL;
            bool in_ground = followed && app_camera_place(app, c, followed, clock->alpha);
            /* A held eye is where the user put it. */
            if (it->entities[i] == app->camera_entity && !app->loading && !app->holding) app->eye_in_solid += in_ground;
            c->view.aspect = (float)width / (float)height;
            c->view.time = time;
            if (streams && viewers < TERRAIN_MAX_VIEWERS) memcpy(eyes[viewers++], c->view.camera, sizeof eyes[0]);
        }
    }
    terrain_view *view = app_view(app);
    terrain_ecs_set_viewers(app->terrain, (const double(*)[3])eyes, viewers);
    terrain_ecs_set_view(app->terrain, view);   /* what the cull phase tests against */
    if (app->grass) grass_set_view(app->grass, view, app_player(app)->position);
    if (app->rocks) rocks_set_view(app->rocks, view);
}

/* tools: the player's tool, aimed from its eye. */
static void app_tools_system(ecs_iter *it) {
    game_app *app = it->user;
    const GameActions *in = ecs_resource_get(it->world, app->ids.actions);
    if (app->loading) return;
    const game_player *pl = app_player(app);
    double eye[3];
    game_player_eye(pl, eye);
    game_tools_update(&app->tools, app->terrain, app->world, eye, pl->yaw, pl->pitch, &in->actions, in->dt);
}

/* terrain_draw: the volumetric chunks and the far terrain (their shadows first). */
static void app_terrain_draw_system(ecs_iter *it) {
    game_app *app = it->user;
    app->drawing_ns = core_time_ns();
    terrain_ecs_draw(app->terrain, app->renderer, app_view(app));
}

/* sky: behind everything drawn so far. */
static void app_sky_system(ecs_iter *it) {
    game_app *app = it->user;
    terrain_renderer_draw_sky(app->renderer, app_view(app));
}

static void app_rocks_draw_system(ecs_iter *it) {
    game_app *app = it->user;
    rocks_draw(app->rocks, app_view(app));
}

static void app_grass_draw_system(ecs_iter *it) {
    game_app *app = it->user;
    grass_draw(app->grass, app_view(app));
}

static void app_water_draw_system(ecs_iter *it) {
    game_app *app = it->user;
    terrain_water_draw(app->water, app->terrain, app->renderer, app_view(app));
}

static void app_hud_system(ecs_iter *it) {
    game_app *app = it->user;
    app_draw_hud(app);
}

static bool app_last_frame(const game_app *app);

/* screenshot: F12's picture, a walk's pictures at its `shot` waypoints, and the run's last
 * picture (--screenshot: the walk's contact sheet, or the last frame). */
static void app_screenshot_system(ecs_iter *it) {
    game_app *app = it->user;
    uint64_t start = core_time_ns();
    if (app->screenshot_wanted) app_take_screenshot(app);
    if (app->walker.shot_due && app->shot_hold++ == 0) app_frame_shot(app);
    else if (app->walker.shot_due && app_shot_ready(app)) {
        app_take_shot(app);
        app->shot_hold = 0;
        game_walker_resume(&app->walker, app_player(app));
    }
    bool last = !app->running || app_last_frame(app);
    if (last && app->desc.screenshot_path) {
        bool written = app->shot_count ? app_write_contact_sheet(app, app->desc.screenshot_path)
                                       : gfx_screenshot(app->gfx, app->desc.screenshot_path);
        if (!written) app->running = false;
    }
    app->over = last;
    app->screenshot_ns = core_time_ns() - start;
}

/* The ids of app.h's game_ids, the player's and its camera's entities. */
static void app_create_entities(game_app *app) {
    ecs_world *ecs = app->ecs;
    game_ids *ids = &app->ids;
    ids->player = ECS_COMPONENT(ecs, GamePlayer);
    ids->camera = ECS_COMPONENT(ecs, GameCamera);
    ids->stream_viewer = ECS_TAG(ecs, GameStreamViewer);
    ids->actions = ECS_RESOURCE(ecs, GameActions);
    ids->clock = ECS_RESOURCE(ecs, GameClock);
    ids->gfx = ecs_resource_register(ecs, &(ecs_resource_desc){ .name = "gfx", .object = app->gfx });
    ids->terrain_world = ecs_resource_register(ecs, &(ecs_resource_desc){ .name = "terrain_world", .object = app->world });
    ids->terrain_ecs = terrain_ecs_resource(app->terrain);
    app->player_entity = ecs_entity_create(ecs);
    ecs_add(ecs, app->player_entity, ids->player);
    app->camera_entity = ecs_entity_create(ecs);
    ecs_set(ecs, app->camera_entity, ids->camera, &(GameCamera){ .follows = app->player_entity });
    ecs_add(ecs, app->camera_entity, ids->stream_viewer);
}

/* The game's systems, after the modules' (their draw-phase uploads come first: each draw system
 * reads what its module's systems write, and all of them write the gfx resource, so they run one
 * after the other in this order). */
static void app_add_systems(game_app *app) {
    ecs_world *ecs = app->ecs;
    const game_ids *ids = &app->ids;
    ecs_component mesh_chunk = ecs_component_lookup(ecs, "TerrainMeshChunk");
    ecs_component water_plane = ecs_component_lookup(ecs, "WaterPlane");
    ecs_component chunk = ecs_component_lookup(ecs, "TerrainChunk");
    ecs_component rock_tiles = ecs_component_lookup(ecs, "RockTiles");   /* 0 with rocks off: last */
    ecs_system_add(ecs, &(ecs_system_desc){ .name = "input", .phase = "input", .fn = app_input_system, .user = app,
        .main_thread = true, .writes = { ids->actions, ids->input }, .reads = { ids->player, ids->terrain_ecs } });
    ecs_system_add(ecs, &(ecs_system_desc){ .name = "player", .phase = "game", .fn = app_player_system, .user = app,
        .main_thread = true, .query = { .with = { ids->player } }, .writes = { ids->player, ids->clock },
        .reads = { ids->actions, ids->terrain_world, mesh_chunk, rock_tiles } });  /* rocks: obstacles */
    ecs_system_add(ecs, &(ecs_system_desc){ .name = "camera", .phase = "game", .fn = app_camera_system, .user = app,
        .main_thread = true, .query = { .with = { ids->camera }, .optional = { ids->stream_viewer } },
        .writes = { ids->camera, ids->terrain_ecs }, .reads = { ids->player, ids->clock, ids->terrain_world } });
    ecs_system_add(ecs, &(ecs_system_desc){ .name = "tools", .phase = "game", .fn = app_tools_system, .user = app,
        .main_thread = true, .reads = { ids->player, ids->actions, mesh_chunk, chunk, rock_tiles },
        .writes = { ids->terrain_ecs, ids->terrain_world } });
    /* The first draw reads every component the modules' draw-phase systems write, so it waits
     * for all of them: a GPU cull that reads its results back (grass) must not queue behind the
     * whole terrain on a software rasteriser. The draws after it follow through `gfx`. */
    ecs_system_desc terrain_draw = { .name = "terrain_draw", .phase = "draw", .fn = app_terrain_draw_system,
        .user = app, .main_thread = true, .writes = { ids->gfx },
        .reads = { ids->camera, mesh_chunk, ids->terrain_ecs, water_plane } };
    int reads = 4;
    ecs_component grass_patch = ecs_component_lookup(ecs, "GrassPatch");
    if (grass_patch) terrain_draw.reads[reads++] = grass_patch;
    if (rock_tiles) terrain_draw.reads[reads++] = rock_tiles;
    ecs_system_add(ecs, &terrain_draw);
    ecs_system_add(ecs, &(ecs_system_desc){ .name = "sky", .phase = "draw", .fn = app_sky_system, .user = app,
        .main_thread = true, .writes = { ids->gfx }, .reads = { ids->camera } });
    if (app->rocks)
        ecs_system_add(ecs, &(ecs_system_desc){ .name = "rocks_draw", .phase = "draw", .fn = app_rocks_draw_system,
            .user = app, .main_thread = true, .writes = { ids->gfx },
            .reads = { ids->camera, rock_tiles, mesh_chunk } });
    if (app->grass)
        ecs_system_add(ecs, &(ecs_system_desc){ .name = "grass_draw", .phase = "draw", .fn = app_grass_draw_system,
            .user = app, .main_thread = true, .writes = { ids->gfx },
            .reads = { ids->camera, grass_patch, mesh_chunk } });
    if (app->water)
        ecs_system_add(ecs, &(ecs_system_desc){ .name = "water_draw", .phase = "draw", .fn = app_water_draw_system,
            .user = app, .main_thread = true, .writes = { ids->gfx },
            .reads = { ids->camera, water_plane, mesh_chunk, ids->terrain_ecs } });
    ecs_system_add(ecs, &(ecs_system_desc){ .name = "hud", .phase = "draw", .fn = app_hud_system, .user = app,
        .main_thread = true, .writes = { ids->gfx }, .reads = { ids->camera, ids->player, ids->terrain_ecs } });
    /* Pictures after every draw, a developer's own draw systems (desc.setup) included. */
    ecs_phase_add(ecs, "present", "draw");
    ecs_system_add(ecs, &(ecs_system_desc){ .name = "screenshot", .phase = "present", .fn = app_screenshot_system,
        .user = app, .main_thread = true, .writes = { ids->gfx, ids->player }, .reads = { ids->camera, ids->terrain_ecs } });
}

/* Detail from a screen-space error follows the framebuffer's height and the view's field of
 * view: the rings and the clipmap are derived again when either changes (a resized window). */
static void app_screen_changed(game_app *app) {
    if (!(app->desc.pixel_error > 0)) return;
    int width, height;
    gfx_size(app->gfx, &width, &height);
    float fov_y = app_view(app)->fov_y;
    if (height <= 0 || (height == app->screen_height && fov_y == app->screen_fov_y)) return;
    app->screen_height = height;
    app->screen_fov_y = fov_y;
    terrain_ecs_stream_set_screen(app->terrain, height, fov_y);
    terrain_stream_desc rings = terrain_ecs_stream_desc(app->terrain);
    if (app->clipmap)
        terrain_clipmap_set_screen(app->clipmap, height, fov_y,
                                   (float)terrain_rings_clearance(rings.half_width, rings.levels, rings.levels - 1));
}

bool game_app_frame(game_app *app) {
    if (app->over) return false;
    app_screen_changed(app);                   /* before the frame's systems use the clipmap */
    trace_frame_begin();
    uint64_t now = core_time_ns(), thread_start = app_thread_cpu_ns();
    app->frame_seconds = (double)(now - app->last_ns) * 1e-9;
    app->last_ns = now;
    app->drawing_ns = now;
    app->screenshot_ns = 0;
    float dt = app->windowed ? (float)app->frame_seconds : app->desc.step_seconds;
    gfx_frame_begin(app->gfx);
    ecs_progress(app->ecs, dt);                /* input, game, stream … draw, background (app.h) */
    /* Every phase: the draw calls, and the background phase's hand-out of jobs after them. */
    uint64_t progressed = core_time_ns() - app->screenshot_ns;
    double cpu_ms = (double)(progressed - now) * 1e-6, engine_ms = (double)(app->drawing_ns - now) * 1e-6;
    double thread_ms = (double)(app_thread_cpu_ns() - thread_start) * 1e-6;
    gfx_frame_end(app->gfx);
    /* The frame's CPU part as the bench rows read it, for `trace_report --over MS --series`: the
     * frame zone itself also holds the wait for the GPU (on llvmpipe, its whole rasterisation). */
    trace_counter("game.cpu_frame_ms", cpu_ms);
    trace_counter("game.thread_cpu_ms", thread_ms);
    app_memory_counters(app);
    job_system_trace_counters(app->jobs); /* the frame's jobs.* counters */
    trace_frame_end();
    if (app->loading) {
        app->loading_frames++;
        if (app_loaded(app)) app_finish_loading(app);
    } else {
        app->frames++;
        app_record_cpu(app, cpu_ms, engine_ms, thread_ms, (double)gfx_context_stats(app->gfx).triangles);
        double grass_ms = app->grass ? grass_system_stats(app->grass).cpu_ms : 0.0;
        app->grass_ms_sum += grass_ms;
        app->grass_ms_max = fmax(app->grass_ms_max, grass_ms);
    }
    if (app->desc.world_dir && (double)(core_time_ns() - app->last_save_ns) * 1e-9 >= GAME_APP_AUTOSAVE_SECONDS)
        app_save(app, false);
    return !app->over;
}

/* ---- results ------------------------------------------------------------------------------ */

static int compare_doubles(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* `count` per-frame values into `sorted`, ascending (for trace_percentile). */
static void app_sorted(const double *values, size_t count, double *sorted) {
    if (count) memcpy(sorted, values, count * sizeof *sorted);
    qsort(sorted, count, sizeof *sorted, compare_doubles);
}


game_app_stats_info game_app_stats(const game_app *app) {
    game_app_stats_info s = { .frames = app->frames, .loading_frames = app->loading_frames,
                         .eye_in_solid_frames = app->eye_in_solid, .waiting_frames = app->waiting };
    memcpy(s.eye, app_view(app)->camera, sizeof s.eye);
    memcpy(s.feet, app_player(app)->position, sizeof s.feet);
    s.flying = app_player(app)->flying;
    s.yaw = app_view(app)->yaw, s.pitch = app_view(app)->pitch;
    app_look_degrees(s.yaw, s.pitch, s.look);
    if (app->desc.walk && !app->loading) {
        s.walked = app->walker.walked;
        s.from_start = app->walker.from_start;
        s.walk_done = app->walker.done;
        s.walk_stuck = app->walker.stuck;
    }
    const size_t n = app->cpu_count;
    double *sorted = core_alloc((n ? n : 1) * sizeof *sorted);
    app_sorted(app->cpu_ms, n, sorted);
    s.cpu_ms_p50 = trace_percentile(sorted, n, 50);
    s.cpu_ms_p99 = trace_percentile(sorted, n, 99);
    s.cpu_ms_max = n ? sorted[n - 1] : 0.0;
    for (size_t i = 0; i < n; i++) s.hitches += app->cpu_ms[i] > APP_HITCH_MS;
    app_sorted(app->engine_ms, n, sorted);
    s.engine_ms_p50 = trace_percentile(sorted, n, 50);
    s.engine_ms_p99 = trace_percentile(sorted, n, 99);
    app_sorted(app->thread_ms, n, sorted);
    s.thread_ms_p50 = trace_percentile(sorted, n, 50);
    s.thread_ms_p99 = trace_percentile(sorted, n, 99);
    app_sorted(app->triangles, n, sorted);
    s.triangles_p50 = trace_percentile(sorted, n, 50);
    core_free(sorted, (n ? n : 1) * sizeof *sorted);
    s.stream = terrain_ecs_stream_stats(app->terrain);
    s.edits = terrain_ecs_edit_stats(app->terrain);
    s.strokes = app->tools.strokes;
    s.edited_chunks = terrain_edit_log_chunks(app->edits);
    if (app->grass) {
        grass_system_stats_info g = grass_system_stats(app->grass);
        s.grass_tufts = g.tufts;
        s.grass_tufts_drawn = g.tufts_drawn;
    }
    if (app->rocks) {
        rocks_system_stats_info r = rocks_system_stats(app->rocks);
        s.rocks_placed = r.instances;
        s.rocks_drawn = r.instances_drawn;
        s.rock_shapes = app->rock_tiles->rock_count;
        s.rocks_build_seconds = app->rock_tiles->build_seconds;
    }
    if (app->cliffs) {
        rocks_cliffs_stats_info c = rocks_cliffs_stats(app->cliffs);
        s.cliffs = true;
        s.cliff_blocks = c.copies_present;
        s.cliff_fields = c.fields;
        s.cliff_cells_computed = c.cells_computed;
        s.cliff_cells_reused = c.cells_reused;
        s.cliffs_amplify_seconds = c.amplify_seconds;
        s.cliffs_presence_seconds = c.presence_seconds;
        s.cliffs_build_seconds = c.build_seconds;
        s.cliff_tiles_from_cache = c.tiles_from_cache;
    }
    s.grass_ms_mean = app->frames ? app->grass_ms_sum / app->frames : 0.0;
    s.grass_ms_max = app->grass_ms_max;
    struct rusage usage;
    if (getrusage(RUSAGE_SELF, &usage) == 0) s.peak_rss_bytes = (size_t)usage.ru_maxrss * 1024;
    return s;
}

const double *game_app_frame_times(const game_app *app, int *count) {
    *count = (int)app->cpu_count;
    return app->cpu_ms;
}

ecs_world *game_app_ecs(game_app *app) { return app->ecs; }
const game_ids *game_app_ids(const game_app *app) { return &app->ids; }
ecs_entity game_app_player(const game_app *app) { return app->player_entity; }
ecs_entity game_app_camera(const game_app *app) { return app->camera_entity; }
terrain_world *game_app_world(game_app *app) { return app->world; }
terrain_ecs *game_app_terrain(game_app *app) { return app->terrain; }
grass_system *game_app_grass(game_app *app) { return app->grass; }
rocks_system *game_app_rocks(game_app *app) { return app->rocks; }
terrain_renderer *game_app_renderer(game_app *app) { return app->renderer; }
bool game_app_loaded(const game_app *app) { return !app->loading; }
