/* app.h — the walkable infinite world as one object: a window (or an offscreen OSMesa context),
 * the job system, the ECS with the terrain's streaming systems and the far clipmap, the player,
 * input (devices, a recording or a scripted walk) and the HUD. game/main.c is a command line
 * around it; the benchmarks and the end-to-end tests drive it directly.
 *
 *     game_app *app = game_app_create(&(game_app_desc){ .seed = 7, .width = 1280, .height = 720 });
 *     if (!app) return 1;                               // the reason is printed
 *     while (game_app_frame(app)) {}                    // until closed, quit or the walk ends
 *     game_app_stats_info stats = game_app_stats(app);
 *     game_app_destroy(app);
 *
 * Start-up: the world streams in around the spawn point while a loading line shows. The player
 * stands still (and, when recording or replaying, input is not read) until the chunks nearest it
 * and its collision chunks are ready, so a recording replays frame for frame whatever the
 * loading took.
 *
 * THE FRAME IS ONE ecs_progress. The game is ECS systems like the terrain's, in the phases of
 * ecs.h, each a trace zone inside its phase's:
 *     input   input                          devices, a recording or its replay → GameActions
 *     game    player, camera, tools          fixed steps of the body; the view; the tool
 *     stream … cull                          the terrain's streaming, meshing, clipmap and culling
 *     draw    terrain_upload, grass_place, … the modules' uploads, then
 *             terrain_draw, sky, rocks_draw, grass_draw, water_draw, hud
 *     present screenshot                     after every draw (a developer's own included)
 * The player is an entity with a GamePlayer, its camera an entity with a GameCamera that follows
 * it, and streaming follows every camera tagged GameStreamViewer: a second viewer (a spectator,
 * split screen) is one more entity. The body moves in fixed steps of GAME_PLAYER_STEP seconds and
 * the camera interpolates between the last two, so a long frame is not slow motion and a walk
 * ends at the same place at any frame rate.
 *
 * ONE PATH FOR EVERY RUN. Nothing generates terrain on the main thread for the player: every run
 * waits at the edge of what has streamed. Interactive play reads input while it waits (the
 * player looks around, standing still); scripted, recorded and replayed runs hold the whole
 * simulation (no input read, no step taken) until the box the player can reach this frame has
 * streamed in, so a replay ends where its recording did however the background jobs ran.
 *
 * EXTENDING THE WORLD. desc.setup runs once the game's systems exist: add components, resources
 * and systems there, with the ids of game_app_ids (tools/examples/game/game_setup_system.c).
 *     static void setup(game_app *app, ecs_world *ecs, void *user) {
 *         const game_ids *ids = game_app_ids(app);
 *         ecs_component sun = ECS_COMPONENT(ecs, SunClock);
 *         ecs_set(ecs, game_app_camera(app), sun, &(SunClock){ 20.0f });
 *         ecs_system_add(ecs, &(ecs_system_desc){ .name = "sun_clock", .phase = "game",
 *             .query = { .with = { ids->camera, sun } }, .writes = { ids->camera },
 *             .reads = { ids->clock }, .fn = sun_clock, .user = (void *)ids });
 *     }
 */
#ifndef GAME_APP_H
#define GAME_APP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "ecs/ecs.h"
#include "input/input.h"
#include "player.h"
#include "rocks/rocks.h"
#include "terrain/terrain.h"
#include "vegetation/vegetation.h"
#include "walk.h"

typedef struct game_app game_app;

/* ---- the game's components and resources ------------------------------------------------- */

#define GAME_PLAYER_STEP (1.0f / 120.0f)   /* seconds of one fixed step of the body */

/* A player's body: the controller's state after the last fixed step, and its feet before it
 * (the camera draws in between). */
typedef struct GamePlayer {
    game_player body;
    double previous[3];
} GamePlayer;

/* A camera: the view drawn from it, following a GamePlayer entity's eye. */
typedef struct GameCamera {
    terrain_view view;
    ecs_entity follows;               /* an entity with a GamePlayer; 0 = a free camera */
} GameCamera;

/* Resource: the frame's input, written by the `input` system. */
typedef struct GameActions {
    input_actions actions;            /* zero when input was not read this frame */
    float dt;                         /* the seconds they stand for (a replay's recorded dt) */
    bool read;                        /* input was read (not loading, not held for streaming) */
} GameActions;

/* Resource: the simulation's clock. */
typedef struct GameClock {
    double seconds;                   /* simulated time, fixed steps × GAME_PLAYER_STEP */
    uint64_t steps;                   /* fixed steps taken */
    double banked;                    /* frame time not yet stepped, [0, GAME_PLAYER_STEP) */
    float alpha;                      /* banked / GAME_PLAYER_STEP: where cameras interpolate */
} GameClock;

/* What a system names in its query, reads and writes. The resources' objects are the gfx
 * context (gfx.h), the terrain world and its ECS streamer (terrain.h) and the input system. */
typedef struct game_ids {
    ecs_component player, camera, stream_viewer;          /* components (the last is a tag) */
    ecs_component actions, clock;                         /* value resources */
    ecs_component gfx, terrain_world, terrain_ecs, input; /* object resources */
} game_ids;

/* Zero means the default for every field. */
typedef struct game_app_desc {
    uint64_t seed;                    /* world seed */
    int width, height;                /* framebuffer; 0 = 1280 × 720 */
    bool headless;                    /* offscreen (OSMesa) even with a display */
    int threads;                      /* job threads, the main one included; 0 = one per core */
    int frames;                       /* stop after this many frames past loading; 0 = never (300
                                         offscreen without a walk or a replay) */
    const game_walk *walk;            /* scripted input (borrowed); NULL = devices */
    const char *record_path;          /* record every frame's input */
    const char *replay_path;          /* play a recording back */
    const char *bindings_path;        /* input bindings; NULL = built-in defaults */
    const char *gamepad_mappings_path; /* SDL mapping lines for pads read through GLFW; NULL = none */
    const char *screenshot_path;      /* written after the last frame */
    double spawn[2];                  /* x, z of the spawn column; the player stands on top */
    bool face_open_view;              /* spawn facing the most open view (game_player_open_yaw);
                                         interactive runs always do, walks keep yaw π (+z) */
    /* A view asked for (world --at, --look), over the spawn, the walk's start and a world
     * folder's pose. at: the eye, world metres; the player flies when standing would move it
     * (the eye in the ground, or nothing within a step below the feet), else stands. look:
     * degrees, yaw 0 along +z and positive to the right (towards −x: terrain_view's yaw is
     * π + yaw), pitch positive up (±89). Either holds the view exactly until input moves or
     * turns the player, so a --frames 1 picture shows just what was asked for. */
    bool at_set, look_set;
    double at[3], look[2];
    /* A world made by hand instead of generated (tests, tools): as terrain_world_desc's. */
    terrain_stacks *(*generate)(void *user, terrain_chunk_coord coord);
    void *generate_user;
    terrain_stream_desc stream;       /* view distance and budgets; zero = defaults */
    int stabilize_iterations;         /* how far sand slides each frame after an edit. 0 = 2 ms
                                         of wall-clock time in interactive play, and 3 iterations
                                         (about that long on this project's 2-core machine) when
                                         recording, replaying or walking a script: an iteration
                                         budget does not depend on the machine, so a replay gives
                                         the recording's world byte for byte */
    float pixel_error;                /* screen-space error target in pixels for the far terrain
                                         and, when stream leaves half_width and levels 0, the
                                         rings (terrain.h, "detail from a screen-space error"),
                                         at the framebuffer's height and the view's field of
                                         view, derived again when the window resizes; 0 = the
                                         fixed rings and clipmap */
    bool no_clipmap;                  /* only the volumetric chunks (no far terrain) */
    bool no_hud;
    grass_quality grass;              /* grass patches (vegetation.h); 0 = low */
    bool no_terrain_detail;           /* the ground without its 1 m detail layer
                                         (terrain_renderer_desc.detail_distance < 0) */
    terrain_shadow_quality shadows;   /* the sun's shadow map (terrain.h); 0 = low */
    terrain_water_quality water;      /* the sea and lakes (terrain.h, terrain_water); 0 = low */
    rocks_quality rocks;              /* rock piles (rocks.h); 0 = on */
    const rocks_tileset *rock_tiles;  /* the rocks' tile set (not owned; tests pass small ones);
                                         NULL = the default set, from rocks_cache_path */
    const char *rocks_cache_path;     /* the default set's cache file; NULL = built each run */
    rocks_quality cliffs;             /* fractured blocks on steep bedrock walls (rocks_cliffs,
                                         paper 003), through the world's amplify hook; 0 = on */
    const char *cliffs_cache_dir;     /* a folder for their block tiles' cache files
                                         (rocks_cliffs_desc.cache_dir); NULL = built each run */
    bool no_head_bob;                 /* the view without the walking dip (game_player_bob) */
    bool no_occlusion;                /* terrain lit without its ambient occlusion
                                         (terrain_renderer_desc.no_occlusion) */
    double max_loading_seconds;       /* give up waiting for the start area; 0 = 300 s */
    float step_seconds;               /* offscreen, the game time each frame steps; 0 = 1/60 s
                                         (a window steps the time the frame took) */
    /* A folder that keeps the world (terrain.h, "the world folder"): DIR/world.db holds the
     * seed, the edits and the player's pose. Loaded at the start (a damaged database is
     * reported and set aside; an old DIR/edits folder is imported once), saved every
     * GAME_APP_AUTOSAVE_SECONDS off the frame thread and at the end; each save is one
     * transaction. Another seed is refused, and so is a world another process has open.
     * Interactive play starts where the last run stood. NULL = edits last as long as the run. */
    const char *world_dir;
    /* Called once at the end of game_app_create, when the game's own systems exist: add your
     * components and systems here (see EXTENDING THE WORLD above). */
    void (*setup)(game_app *app, ecs_world *ecs, void *user);
    void *setup_user;
} game_app_desc;

#define GAME_APP_AUTOSAVE_SECONDS 30.0

/* The seed the world folder records (DIR/world.db, or an old folder's DIR/world.txt): 1 and
 * *seed set; 0 when it records none (a new world); −1 when world.txt exists but does not say
 * "seed N". */
int game_world_dir_seed(const char *dir, uint64_t *seed);

/* NULL (with the reason printed) when the window, the shaders, the bindings or a recording
 * cannot be opened. */
game_app *game_app_create(const game_app_desc *desc);
/* One frame; false once the run is over (window closed, quit action, frame limit, walk done,
 * or the recording ended). */
bool game_app_frame(game_app *app);
void game_app_destroy(game_app *app);

typedef struct game_app_stats_info {
    int frames;                       /* past loading */
    int loading_frames;
    double eye[3], feet[3];           /* of the player now */
    bool flying;
    float yaw, pitch;                 /* the view's, radians (terrain_view's convention) */
    double look[2];                   /* the same as --look takes it (game_app_desc.look) */
    int eye_in_solid_frames;          /* frames whose eye had field ≥ 0: must stay 0 (a view
                                         held as game_app_desc.at asked is not counted) */
    int waiting_frames;               /* frames the player waited for terrain */
    double walked, from_start;        /* the walk's path length and straight-line distance, m */
    bool walk_done, walk_stuck;
    /* Time of each frame past loading on the main thread's clock: from its start to the
     * hand-over to the GL driver (gfx_frame_end), i.e. every phase and the draw calls (a
     * screenshot's read-back of the frame left out). The
     * driver's waits inside the calls count: on llvmpipe, a read of the frame (water's copy for
     * refraction) waits there for the whole scene to be rasterised. */
    double cpu_ms_p50, cpu_ms_p99, cpu_ms_max;
    /* The main thread's own CPU time over the same span (CLOCK_THREAD_CPUTIME_ID): our work and
     * the driver's on this thread (llvmpipe's vertex shading and binning), not its waits. */
    double thread_ms_p50, thread_ms_p99;
    /* The same less the draw calls (terrain_ecs_draw and the HUD): input, player, every phase
     * and the uploads. On llvmpipe the draw calls include the vertex shading a GPU does. */
    double engine_ms_p50, engine_ms_p99;
    /* Triangles drawn a frame (gfx_context_stats: every module's draws, the grass's GPU-generated ones
     * not included), the median over the frames past loading. */
    double triangles_p50;
    int hitches;                      /* frames past loading whose CPU time exceeded 33 ms */
    terrain_ecs_stream_stats_info stream;
    terrain_ecs_edit_stats_info edits;
    uint64_t strokes;                 /* tool strokes the player made */
    int edited_chunks;                /* chunks with logged edits */
    size_t peak_rss_bytes;            /* of the process (getrusage), driver memory included */
    /* Grass (vegetation.h) past loading: CPU ms a frame placing and drawing it, and the tufts
     * placed and drawn in the last frame. */
    double grass_ms_mean, grass_ms_max;
    uint64_t grass_tufts, grass_tufts_drawn;
    /* Rocks (rocks.h): placed now, drawn in the last frame, and the tile set's build seconds
     * (0 when read from its cache). */
    uint64_t rocks_placed, rocks_drawn;
    uint32_t rock_shapes;
    double rocks_build_seconds;
    /* Cliff blocks (rocks_cliffs): on or not, the block copies raised into the fields made so
     * far, those fields, the tile cells whose presence was worked out and those reused, and
     * their tiles' seconds (built or read from the cache) and how many were read. */
    bool cliffs;
    uint64_t cliff_blocks, cliff_fields, cliff_cells_computed, cliff_cells_reused;
    double cliffs_build_seconds, cliffs_amplify_seconds, cliffs_presence_seconds;
    uint32_t cliff_tiles_from_cache;
} game_app_stats_info;

game_app_stats_info game_app_stats(const game_app *app);
/* The ECS and the ids of the game's components and resources (for desc.setup). */
ecs_world *game_app_ecs(game_app *app);
const game_ids *game_app_ids(const game_app *app);
/* The player's and its camera's entities. */
ecs_entity game_app_player(const game_app *app);
ecs_entity game_app_camera(const game_app *app);
/* The world and its ECS terrain, for code that extends the game (edits, more viewers, probes). */
terrain_world *game_app_world(game_app *app);
terrain_ecs *game_app_terrain(game_app *app);
grass_system *game_app_grass(game_app *app);     /* NULL with grass off */
rocks_system *game_app_rocks(game_app *app);     /* NULL with rocks off */
terrain_renderer *game_app_renderer(game_app *app);
/* Whether the start area has loaded (the player moves from then on). */
bool game_app_loaded(const game_app *app);
/* The frame's CPU times (ms) past loading, in order; count in *count. */
const double *game_app_frame_times(const game_app *app, int *count);

#endif
