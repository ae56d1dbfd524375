/* fuzz_checksum.h — what the fuzz targets of checksummed files (fuzz_block_cache, fuzz_tile_cache)
 * do with each input. A mutated file almost never keeps its checksum, so the input is parsed twice:
 * as it is, and with the trailing 8-byte checksum (core_hash_bytes of every byte before it, from
 * `seed`) recomputed over the mutated bytes, which lets the fuzzer reach the checks behind it. An
 * input the fix leaves unchanged must get the same answer both times; one it changes (a wrong
 * checksum) must be refused as it is. `parse` checks its own contract and traps when it breaks. */
#ifndef FUZZ_CHECKSUM_H
#define FUZZ_CHECKSUM_H

#include "core/core.h"

#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

static inline void fuzz_with_checksum(const unsigned char *bytes, size_t size, uint64_t seed,
                                      bool (*parse)(const unsigned char *bytes, size_t size)) {
    bool as_is = parse(bytes, size);
    if (size < 8) return;
    unsigned char *fixed = malloc(size);
    memcpy(fixed, bytes, size);
    uint64_t sum = core_hash_bytes(fixed, size - 8, seed);
    memcpy(fixed + size - 8, &sum, 8);
    bool unchanged = memcmp(fixed, bytes, size) == 0;
    bool with_sum = parse(fixed, size);
    if (unchanged && as_is != with_sum) __builtin_trap();
    if (!unchanged && as_is) __builtin_trap();   /* a wrong checksum got through */
    free(fixed);
}

#endif
