#include "bench.h"
/* placeholder: gfx.frame rows are being written */
void bench_group_gfx(bench_context *ctx) { (void)ctx; }
