#version 450 core
// text.vert — HUD text quads, positioned in pixels from the top-left corner of the screen.

layout(location = 0) in vec3 a_position;     // pixels (z unused)
layout(location = 1) in vec4 a_color;        // unorm8

uniform vec2 u_screen_size;                  // pixels

out vec4 v_color;

void main() {
    vec2 ndc = a_position.xy / u_screen_size * 2.0 - 1.0;
    gl_Position = vec4(ndc.x, -ndc.y, 0.0, 1.0);
    v_color = a_color;
}
