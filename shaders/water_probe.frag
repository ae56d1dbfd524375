#version 450 core
// water_probe.frag — the water's surfaces drawn only for the depth test, no colour written: an
// occlusion query counts whether any of them shows (terrain_water.c skips the shading and the
// frame's copy while none does).

layout(early_fragment_tests) in;

void main() {}
