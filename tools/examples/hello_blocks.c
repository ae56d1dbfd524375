/* hello_blocks — fractured rock blocks on a cliff (paper 003): one block tile of the type asked
 * for, replicated over a vertical wall where its blocks straddle the wall's face, f̃ = max(f, t),
 * then meshed and drawn with the terrain's renderer from a camera that swings along the wall.
 *
 *   hello_blocks [--type equidimensional|rhombohedral|polyhedral|tabular|columnar]
 *                [--size WxH] [--headless] [--frames N] [--screenshot FILE] [--trace FILE]
 */
#include "core/core.h"
#include "gfx/gfx.h"
#include "rocks/rocks.h"
#include "terrain/terrain.h"
#include "trace/trace.h"

#include <math.h>
#include <stdio.h>

#define STEP 0.25f                    /* sample spacing, metres */
#define NX 56                         /* x ∈ [−8, 6): the wall's face is x = 0, solid behind */
#define NY 72                         /* y ∈ [−2, 16): a floor at y = 0 */
#define NZ 96                         /* z ∈ [−12, 12) */

/* The smooth base terrain: a wall (solid for x < 0) standing on a floor (solid for y < 0). */
static float wall(double x, double y) { return (float)fmax(-x, -y); }

/* 003 §5's presence: a block copy is kept where it straddles the wall's face (its box reaches
 * 0.3 m into the wall and 0.3 to 3 m out of it, inside the sampled box), above the floor. `anchor` is the copy's anchor in
 * the world; the block's own anchor gives the copy's offset, hence its box. */
static bool on_the_face(void *user, uint32_t block, const double anchor[3]) {
    const rocks_block *b = &((const rocks_block_tile *)user)->blocks[block];
    double offset = anchor[0] - b->anchor[0], margin = 1.0;   /* bounds hold a metre of margin */
    double back = offset + b->bounds_min[0] + margin, front = offset + b->bounds_max[0] - margin;
    return back < -0.3 && front > 0.3 && front < 3.0 && anchor[1] > 0.5;
}

int main(int argc, char **argv) {
    core_common_args common = { 0 };
    const char *size = NULL, *screenshot = NULL, *type_name = NULL;
    int frames = 0;
    bool headless = false;
    const core_option options[] = {
        CORE_COMMON_OPTIONS(common),
        { "type", CORE_OPTION_STRING, &type_name, "TYPE", "block type (default tabular)" },
        { "size", CORE_OPTION_STRING, &size, "WxH", "framebuffer size (default 1280x720)" },
        { "headless", CORE_OPTION_FLAG, &headless, NULL, "render offscreen with OSMesa" },
        { "frames", CORE_OPTION_INT, &frames, "N", "stop after N frames (0 = when closed)", 0, 100000000 },
        { "screenshot", CORE_OPTION_STRING, &screenshot, "FILE", "write the last frame as a PNG" },
    };
    core_cli cli = { .program = "hello_blocks", .summary = "fractured rock blocks on a cliff",
                     .options = options, .option_count = CORE_COUNTOF(options) };
    int rc = core_cli_parse(&cli, argc, argv);
    if (rc != CORE_CLI_OK) return rc == CORE_CLI_HELP ? 0 : 2;
    rocks_block_type type = ROCKS_BLOCK_TABULAR;
    int width = 1280, height = 720;
    if ((type_name && !rocks_parse_block_type(type_name, &type)) || (size && !gfx_parse_size(size, &width, &height))) {
        fprintf(stderr, "hello_blocks: bad value for '%s'\n", type_name && !rocks_parse_block_type(type_name, &type) ? "--type" : "--size");
        core_cli_print_usage(&cli, stderr);
        return 2;
    }
    if (common.trace_path && !trace_start(common.trace_path)) return 2;

    /* The tile, then the amplified field f̃ = max(f, t) on a grid, meshed once. */
    rocks_block_tile *tile = rocks_block_tile_create(&(rocks_block_tile_desc){ .type = type });
    if (!tile) return 1;
    terrain_field field = { .nx = NX, .ny = NY, .nz = NZ, .origin = { -8, -2, -12 }, .spacing = STEP };
    field.values = core_alloc((size_t)NX * NY * NZ * sizeof *field.values);
    uint64_t start = core_time_ns();
    for (int z = 0; z < NZ; z++)
        for (int y = 0; y < NY; y++)
            for (int x = 0; x < NX; x++) {
                double p[3] = { field.origin[0] + x * STEP, field.origin[1] + y * STEP, field.origin[2] + z * STEP };
                float t = rocks_block_tile_field(tile, p, on_the_face, tile, NULL);
                field.values[((size_t)z * NY + y) * NX + x] = fmaxf(wall(p[0], p[1]), t);
            }
    double field_ms = (double)(core_time_ns() - start) * 1e-6;
    terrain_mesh mesh;
    if (!terrain_mesh_build(&field, &(terrain_mesh_desc){ 0 }, &mesh)) return 1;
    core_free(field.values, (size_t)NX * NY * NZ * sizeof *field.values);

    gfx_context *gfx = gfx_create(&(gfx_desc){ .width = width, .height = height, .title = "hello_blocks", .headless = headless });
    if (!gfx) return 1;
    terrain_renderer *renderer = terrain_renderer_create(gfx, &(terrain_renderer_desc){ .sea_level = -100 });
    if (!renderer) return 1;
    terrain_gpu_mesh gpu = terrain_gpu_mesh_upload(&mesh);

    int status = 0;
    if (!frames && gfx_backend_get(gfx) == GFX_BACKEND_OFFSCREEN) frames = 30;
    terrain_view view = { .pitch = -0.15f, .aspect = (float)width / (float)height,
                          .sun_direction = { 0.55f, 0.6f, 0.58f } };   /* low, across the face */
    for (int frame = 0; (!frames || frame < frames) && !gfx_window_should_close(gfx); frame++) {
        double swing = 0.5 * sin(frame * 0.01);         /* along the wall, looking at it */
        view.camera[0] = 11.0, view.camera[1] = 7.0, view.camera[2] = 8.0 * swing;
        view.yaw = (float)(-M_PI / 2 + 0.3 * swing);     /* facing −x */
        gfx_frame_begin(gfx);
        terrain_renderer_draw(renderer, &view, &gpu, 1);
        if (screenshot && frames && frame + 1 == frames && !gfx_screenshot(gfx, screenshot)) status = 1;
        gfx_frame_end(gfx);
    }
    printf("hello_blocks: %s tile: %u blocks from %u points and %u fractures in %.2f s; "
           "field %.0f ms, %u triangles\n", rocks_block_type_name(type), tile->block_count, tile->sample_count,
           tile->disc_count, tile->build_seconds, field_ms, mesh.index_count / 3);
    terrain_gpu_mesh_destroy(&gpu);
    terrain_mesh_free(&mesh);
    rocks_block_tile_destroy(tile);
    terrain_renderer_destroy(renderer);
    gfx_destroy(gfx);
    trace_stop();
    return status;
}
