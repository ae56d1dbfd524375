/* terrain.h — volumetric terrain: material stacks, 3D-noise generation, the convolution implicit
 * field, marching-cubes meshes, their rendering and the systems that run them in an ECS world.
 *
 * The module is four areas, each a folder with its own public header (which opens with a doc
 * block of its own) and a private one. This header includes the four, so
 * `#include "terrain/terrain.h"` gives the whole API:
 *
 *   data/    terrain/data/terrain_data.h        materials, packed stacks, generation and noise,
 *                                               the world's chunk cache, the implicit field,
 *                                               meshes and levels of detail, field and mesh
 *                                               files, screen-space errors, water planes, the
 *                                               edit log, the world folder (terrain_store),
 *                                               commits of edited chunks
 *   edit/    terrain/edit/terrain_edit.h        column regions, stabilization, brushes,
 *                                               sculpting, sweeping, picking, a tool applied to
 *                                               the world (terrain_world_edit)
 *   render/  terrain/render/terrain_render.h    GPU meshes, the renderer, views and frusta, sun
 *                                               shadows, the far terrain's geometry clipmaps
 *   ecs/     terrain/ecs/terrain_ecs.h          chunks as entities and their systems,
 *                                               streaming, edits in a running world, drawing
 *                                               water
 *
 * Dependencies point one way: edit/ and render/ build on data/, ecs/ on all three; data/ needs
 * neither OpenGL nor the ECS. A file that needs one area may include its header alone.
 * Private declarations are in each area's *_internal.h (data/terrain_data_internal.h, …);
 * terrain/terrain_internal.h includes all four for the module's tests and benchmarks.
 *
 *     #include "terrain/terrain.h"
 *     terrain_world *world = terrain_world_create(&(terrain_world_desc){
 *         .generation = terrain_generation_defaults(42) });              // data/
 *     terrain_ecs *te = terrain_ecs_create(&(terrain_ecs_desc){ .ecs = ecs, .terrain = world });   // ecs/
 *     terrain_ecs_spawn_rings(te, 2, 3, -64, 160);
 *     each frame:  ecs_progress(ecs, dt);  terrain_ecs_draw(te, renderer, &view);   // render/
 *
 * modules/terrain/README.md lists every file of each area and what it holds.
 */
#ifndef TERRAIN_H
#define TERRAIN_H

#include "terrain/data/terrain_data.h"
#include "terrain/edit/terrain_edit.h"
#include "terrain/render/terrain_render.h"
#include "terrain/ecs/terrain_ecs.h"

#endif
