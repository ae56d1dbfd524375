/* fuzz_field_header — libFuzzer target for the field file header parser
 * (terrain_field_header_parse, modules/terrain/data/terrain_field_file.c).
 *
 *   tests/fuzz/run.sh 20     (builds every target with the engine's sources, runs each 20 s)
 * Seeds: tests/fuzz/corpus/fuzz_field_header/ (a valid header, a negative origin, missing and
 * mistyped keys, out-of-range dims).
 *
 * Besides "no crash, no leak, no read out of bounds" it traps when a result breaks the parser's
 * contract: a failure always says why, and a success always gives dims in 1 … the limit, a
 * finite origin and a finite positive spacing.
 */
#include "core/core.h"
#include "terrain/terrain.h"

#include <math.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const unsigned char *bytes, size_t size);

int LLVMFuzzerTestOneInput(const unsigned char *bytes, size_t size) {
    terrain_field_header header;
    core_error error = { 0 };
    if (terrain_field_header_parse((const char *)bytes, size, &header, &error)) {
        for (int a = 0; a < 3; a++) {
            if (header.dims[a] < 1 || header.dims[a] > TERRAIN_FIELD_FILE_MAX_DIM) __builtin_trap();
            if (!isfinite(header.origin[a])) __builtin_trap();
        }
        if (!(header.spacing > 0.0f) || !isfinite(header.spacing)) __builtin_trap();
    } else {
        if (error.code != CORE_ERROR_FORMAT && error.code != CORE_ERROR_RANGE) __builtin_trap();
        if (error.message[0] == '\0' || memchr(error.message, '\0', sizeof error.message) == NULL) __builtin_trap();
        if (header.dims[0] != 0 || header.spacing != 0.0f) __builtin_trap();   /* zeroed on failure */
    }
    return 0;
}
