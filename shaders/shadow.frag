#version 450 core
// shadow.frag — depth only: the shadow map keeps the rasterised depth, no colour is written.

void main() {
}
