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

// The share of tufts standing at a distance falls linearly from 0.4·range to range; each tuft
// shrinks out over a short span of that share, so density changes without a ring. 0 = gone.
float grass_scale(uint seed, float distance, float range) {
    float shown = clamp((range - distance) / (0.6 * range), 0.0, 1.0);
    return clamp((shown - grass_unit(grass_hash(seed ^ 0x68e31da4u))) * 6.0, 0.0, 1.0);
}

// A tuft's height: around `average`, less where the ground carries grass thinly (grow < 1).
float grass_tuft_height(uint seed, float grow, float scale, float average) {
    return average * (0.6 + 0.8 * grass_unit(grass_hash(seed ^ 0xb5297a4du))) * (0.55 + 0.45 * grow) * scale;
}
