#include "bench.h"
/* placeholder: rows being written */
void bench_group_terrain_mesh(bench_context *ctx) { (void)ctx; }
