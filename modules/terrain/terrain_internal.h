/* terrain_internal.h — the terrain module's private declarations, all four areas at once: for
 * the module's tests and benchmarks, which reach into more than one area. The module's own files
 * include their area's header instead (data/terrain_data_internal.h, edit/…, render/…, ecs/…;
 * terrain.h says what each area holds). Nothing outside modules/terrain, tests/ and tools/src/bench
 * includes this; the public API is terrain.h.
 */
#ifndef TERRAIN_INTERNAL_H
#define TERRAIN_INTERNAL_H

#include "terrain/terrain.h"

#include "terrain/data/terrain_data_internal.h"
#include "terrain/edit/terrain_edit_internal.h"
#include "terrain/render/terrain_render_internal.h"
#include "terrain/ecs/terrain_ecs_internal.h"

#endif
