/* vegetation_internal.h — what the vegetation module's files share; not for other modules. */
#ifndef VEGETATION_INTERNAL_H
#define VEGETATION_INTERNAL_H

#include "gfx/gfx.h"

/* The blades every tuft shows: RGBA, alpha 0 between blades, mipmapped, clamped. Main thread. */
gfx_texture grass__blade_texture(void);

#endif
