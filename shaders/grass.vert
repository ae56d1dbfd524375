#version 450 core
// grass.vert — one tuft per instance, two crossed quads (12 vertices) around an up halfway between
// the ground's normal and the vertical (002 §3.3 uses the normal alone, which tilts tufts on
// slopes more than grass grows). No vertex buffer: the tufts come from the patch's buffer.
// Drawn camera-relative like the terrain: u_offset = patch origin − camera, in double on the CPU.

#include "grass.glsl"

layout(std430, binding = 0) readonly buffer Tufts { vec4 tufts[]; };

uniform mat4 u_view_projection;
uniform vec3 u_offset;
uniform vec2 u_wave_offset;        // patch origin modulo the gusts' period: where the gust is
uniform vec3 u_player;             // the player's feet − camera; far away when nothing bends
uniform float u_time;
uniform float u_range;             // the last tuft stands here
uniform float u_height;            // an average tuft, metres

out vec2 v_uv;                     // across the blade texture; y 0 at the root, 1 at the top
out vec3 v_relative_position;
out vec3 v_normal;
out vec3 v_tint;

const int CORNERS[6] = int[6](0, 1, 2, 2, 1, 3);   // 0, 1 at the root; 2, 3 at the top
const vec2 WIND = vec2(0.8, 0.6);

void main() {
    vec4 a = tufts[2 * gl_InstanceID], b = tufts[2 * gl_InstanceID + 1];
    uint seed = floatBitsToUint(a.w);
    vec3 root = a.xyz + u_offset;
    // The share of tufts standing at this distance falls linearly from 0.4·range to range; each
    // tuft shrinks out over a short span of that share, so the density changes without a ring.
    float shown = clamp((u_range - length(root)) / (0.6 * u_range), 0.0, 1.0);
    float scale = clamp((shown - grass_unit(grass_hash(seed ^ 0x68e31da4u))) * 6.0, 0.0, 1.0);
    if (scale <= 0.0) {
        gl_Position = vec4(0.0, 0.0, 2.0, 1.0);       // beyond the far plane: nothing drawn
        return;
    }
    float grow = b.w;
    float height = u_height * (0.6 + 0.8 * grass_unit(grass_hash(seed ^ 0xb5297a4du))) * (0.55 + 0.45 * grow) * scale;
    int quad = gl_VertexID / 6, corner = CORNERS[gl_VertexID % 6];
    vec3 normal = normalize(b.xyz);
    vec3 up = normalize(normal + vec3(0.0, 1.0, 0.0));
    float turn = grass_unit(grass_hash(seed ^ 0x1b56c4e9u)) * 3.14159265 + float(quad) * 1.5707963;
    vec3 across = vec3(cos(turn), 0.0, sin(turn));
    vec3 side = normalize(across - up * dot(across, up));
    vec3 position = root + side * (float(corner & 1) - 0.5) * height * 1.1;
    if (corner >= 2) {
        vec3 tip = up * height;
        // Gusts travel across the field; each tuft adds its own flutter.
        vec2 world_xz = a.xz + u_wave_offset;
        float gust = sin(dot(world_xz, WIND) * 0.35 - u_time * 1.9) * 0.5 + 0.5;
        float flutter = sin(u_time * 3.1 + grass_unit(seed) * 6.2831853) * 0.35;
        tip.xz += WIND * (gust * 0.35 + flutter * 0.15) * height;
        // Bent away from the player's feet within about a metre and a half.
        vec3 away = position + tip - u_player;
        float reach = (1.0 - smoothstep(0.3, 1.5, length(away.xz))) * (1.0 - smoothstep(1.0, 2.0, abs(root.y - u_player.y)));
        vec2 outwards = length(away.xz) > 1e-3 ? normalize(away.xz) : vec2(1.0, 0.0);
        tip.xz += outwards * reach * height * 0.9;
        tip.y -= reach * height * 0.45;
        position += tip;
    }
    float hue = grass_unit(grass_hash(seed ^ 0x2c1b3c6du));
    v_tint = mix(vec3(0.85, 0.92, 0.80), vec3(1.15, 1.08, 0.90), hue);
    v_uv = vec2(float(corner & 1), corner >= 2 ? 1.0 : 0.0);
    v_relative_position = position;
    v_normal = normal;
    gl_Position = u_view_projection * vec4(position, 1.0);
}
