#include "../engine/test.h"
#include "terrain/terrain.h"
/* placeholder so the runner builds */
Test(terrain_placeholder, builds) { cr_assert(1); }
