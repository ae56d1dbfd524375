/* terrain_rings — the terrain module in one short program: column chunks and mesh chunks as
 * entities, generated and meshed in parallel by the generate and mesh phases, culled, and drawn
 * with triplanar materials while the camera circles the start. The walkable, streaming world
 * is game/ (the world program); this shows the module alone.
 *
 *   terrain_rings [--seed S] [--radius R] [--rings N] [--size WxH] [--headless] [--frames N]
 *                 [--screenshot FILE] [--threads N] [--trace FILE]
 *
 * Full detail covers 2R × 2R chunks of 32 m around the start; each of N rings beyond it is meshed
 * at half the resolution of the one inside, out to 2R·32·2^N metres, with closed seams.
 */
#include "core/core.h"
#include "ecs/ecs.h"
#include "gfx/gfx.h"
#include "input/input.h"
#include "jobs/jobs.h"
#include "terrain/terrain.h"
#include "trace/trace.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct options {
    core_common_args common;
    const char *size, *screenshot;
    int seed, radius, rings, frames;
    bool headless;
} options;

static int parse(int argc, char **argv, options *o, int *width, int *height) {
    const core_option list[] = {
        CORE_COMMON_OPTIONS(o->common),
        { "seed", CORE_OPTION_INT, &o->seed, "S", "world seed", 0, 2147483647 },
        { "radius", CORE_OPTION_INT, &o->radius, "R", "full-detail chunks each way from the start (default 2)", 1, 16 },
        { "rings", CORE_OPTION_INT, &o->rings, "N", "coarser rings of detail beyond (default 2)", 0, 5 },
        { "size", CORE_OPTION_STRING, &o->size, "WxH", "framebuffer size (default 1280x720)" },
        { "headless", CORE_OPTION_FLAG, &o->headless, NULL, "render offscreen with OSMesa" },
        { "frames", CORE_OPTION_INT, &o->frames, "N", "stop after N frames (0 = when closed)", 0, 100000000 },
        { "screenshot", CORE_OPTION_STRING, &o->screenshot, "FILE", "write the last frame as a PNG" },
    };
    core_cli cli = { .program = "terrain_rings", .summary = "generate, mesh and draw terrain",
                     .options = list, .option_count = CORE_COUNTOF(list) };
    o->seed = 1;
    o->radius = 2;
    o->rings = 2;
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    *width = 1280;
    *height = 720;
    if (o->size && !gfx_parse_size(o->size, width, height)) {
        fprintf(stderr, "terrain_rings: bad value for '--size': '%s' is not WxH (16 to 16384 each)\n", o->size);
        core_cli_print_usage(&cli, stderr);
        return 2;
    }
    return -1;
}

/* Frame rate, chunk counts, position and seed in the top-left corner (text half as big in a
 * frame under 960 pixels wide, where the lines would not fit). */
static void draw_hud(gfx_text *hud, terrain_ecs *te, const terrain_view *view, double frame_seconds, int seed,
                     int width) {
    terrain_ecs_stats_info s = terrain_ecs_stats(te);
    const float white[4] = { 1, 1, 1, 1 };
    int scale = width < 960 ? 1 : 2, line = 11 * scale;
    gfx_text_print(hud, 8, 8, scale, white, "%.0f fps  %.1f ms", frame_seconds > 0 ? 1.0 / frame_seconds : 0.0,
                   frame_seconds * 1e3);
    gfx_text_print(hud, 8, 8 + line, scale, white, "chunks %d of %d meshed, %d waiting, %.2f M triangles",
                   s.mesh_chunks_uploaded, s.mesh_chunks, s.mesh_chunks_waiting, (double)s.triangles * 1e-6);
    gfx_text_print(hud, 8, 8 + 2 * line, scale, white, "x %.1f  y %.1f  z %.1f  seed %d", view->camera[0],
                   view->camera[1], view->camera[2], seed);
    gfx_text_draw(hud);
}

int main(int argc, char **argv) {
    options o = { 0 };
    int width, height;
    int rc = parse(argc, argv, &o, &width, &height);
    if (rc >= 0) return rc;
    if (o.common.trace_path && !trace_start(o.common.trace_path)) return 2;
    trace_thread_name("main");
    gfx_context *gfx = gfx_context_create(&(gfx_context_desc){ .width = width, .height = height, .title = "terrain_rings (loading)",
                                               .headless = o.headless });
    if (!gfx) return 1;
    job_system *jobs = job_system_create(&(job_system_desc){ .threads = o.common.threads });
    ecs_world *ecs = ecs_world_create(&(ecs_world_desc){ .jobs = jobs });
    terrain_generation_desc params = terrain_generation_defaults((uint64_t)o.seed);
    terrain_world *world = terrain_world_create(&(terrain_world_desc){ .generation = params });
    terrain_renderer *renderer = terrain_renderer_create(gfx, &(terrain_renderer_desc){ .sea_level = params.sea_level });
    gfx_text *hud = gfx_text_create(gfx);
    /* Input only to notice Escape and the window closing. */
    input_system *input = input_system_create(&(input_system_desc){ .glfw_window = gfx_glfw_window(gfx) }, NULL);
    if (!renderer || !hud || !input) return 1;
    terrain_ecs *te = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = ecs, .terrain = world });
    /* Mesh layers that cover the relief, with a margin for overhangs. */
    double low = params.base_height - params.relief_height - 48, high = params.base_height + params.relief_height + 48;
    terrain_ecs_spawn_rings(te, 2 * o.radius, o.rings + 1, low, high);

    /* The camera circles the start 40 m above the ground there, looking ahead and a little down. */
    double ground = terrain_stacks_surface(terrain_world_stacks(world, (terrain_chunk_coord){ 0, 0 }), 0, 0);
    terrain_view view = { .pitch = -0.25f };
    bool windowed = gfx_backend_get(gfx) == GFX_BACKEND_WINDOW;
    int frames = o.frames ? o.frames : (windowed ? 0 : 30);
    uint64_t start = core_time_ns(), last = start;
    for (int frame = 0; frames == 0 || frame < frames; frame++) {
        if (!input_update(input, 1.0f / 60.0f) || gfx_window_should_close(gfx) ||
            (input_actions_get(input)->pressed & INPUT_ACTION_BIT(INPUT_ACTION_QUIT)))
            break;
        trace_frame_begin();
        uint64_t now = core_time_ns();
        double frame_seconds = (double)(now - last) * 1e-9;
        last = now;
        float t = windowed ? (float)((now - start) * 1e-9) : (float)frame / 60.0f;
        view.yaw = 0.05f * t;
        view.camera[0] = 60.0 * sin(view.yaw) + 16.0;
        view.camera[1] = ground + 40.0;
        view.camera[2] = 60.0 * cos(view.yaw) + 16.0;
        gfx_size(gfx, &width, &height);
        view.aspect = (float)width / (float)height;
        view.time = t;
        terrain_ecs_set_view(te, &view);          /* what the cull phase tests against */
        gfx_frame_begin(gfx);
        ecs_progress(ecs, 1.0f / 60.0f);           /* generate, mesh, cull and upload */
        terrain_ecs_draw(te, renderer, &view);
        draw_hud(hud, te, &view, frame_seconds, o.seed, width);
        if (o.screenshot && frames && frame + 1 == frames && !gfx_screenshot(gfx, o.screenshot)) rc = 1;
        gfx_frame_end(gfx);
        trace_frame_end();
        if (frame == 0) gfx_window_set_title(gfx, "terrain_rings");   /* the first frame is meshed */
    }
    terrain_ecs_stats_info stats = terrain_ecs_stats(te);
    printf("terrain_rings: %d chunks, %d mesh chunks (%d drawn), %llu triangles, %llu frames\n", stats.chunks,
           stats.mesh_chunks, stats.mesh_chunks_uploaded, (unsigned long long)stats.triangles,
           (unsigned long long)gfx_frame_index(gfx));
    input_system_destroy(input);
    gfx_text_destroy(hud);
    terrain_ecs_destroy(te);
    terrain_renderer_destroy(renderer);
    ecs_world_destroy(ecs);
    terrain_world_destroy(world);
    job_system_destroy(jobs);
    gfx_context_destroy(gfx);
    trace_stop();
    return rc < 0 ? 0 : rc;
}

/* Expected output:
 * Run: --headless --size 96x64 --radius 1 --rings 1 --frames 2 --seed 3 --screenshot $TMP/terrain.png
 * ^terrain_rings: 16 chunks, [0-9]+ mesh chunks \([0-9]+ drawn\), [1-9][0-9]* triangles, 2 frames$
 */
