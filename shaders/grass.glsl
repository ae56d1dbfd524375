// grass.glsl — what grass placement and drawing share: an integer hash (no sin(): the same bits
// on every GPU, so tufts stand in the same place on every machine and every run).

// An avalanche mix of 32 bits (the "lowbias32" constants).
uint grass_hash(uint x) {
    x ^= x >> 16; x *= 0x7feb352du;
    x ^= x >> 15; x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

uint grass_hash3(uint a, uint b, uint c) { return grass_hash(a ^ grass_hash(b ^ grass_hash(c))); }

// [0, 1) from the top 24 bits.
float grass_unit(uint h) { return float(h >> 8) * (1.0 / 16777216.0); }
