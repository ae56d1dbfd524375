#include "bench.h"
/* placeholder: input.decode rows are being written */
void bench_group_input(bench_context *ctx) { (void)ctx; }
