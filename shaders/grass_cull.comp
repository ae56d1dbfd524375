#version 450 core
// grass_cull.comp — each frame, the tufts of one patch that can show (inside the view's frustum
// and not yet faded out with distance) are shaped and appended to one buffer for all patches,
// and counted in the one indirect draw. A patch is 32 or 64 m wide, and most of its tufts are out
// of view or range: only the others reach the vertex stage, and the work of a tuft (its height,
// turn, colour, the wind and the player's push) is done here once, not at each of its corners.
// The CPU already left out the parts of the mesh (each a run of tufts) whose boxes are out of
// view or range: an invocation takes the runs in view one after another.
//
// A tuft is two crossed quads around an up halfway between the ground's normal and the vertical
// (002 §3.3 uses the normal alone, which tilts tufts on slopes more than grass grows). A tuft is
// lit with the ground's normal (so far tufts take the ground's shading and melt into its grass
// tint) and fogged at its root, here, once: the fragments only read the blade texture. Written
// per tuft, five vec4: (root, fog), (first quad's half side, light.r), (second quad's half side,
// light.g), (root-to-top, light.b), (fog colour, 0); roots camera-relative, as the terrain is
// drawn (common.glsl's u_camera_position is then 0).

#include "common.glsl"
#include "grass.glsl"

layout(local_size_x = 64) in;

layout(std430, binding = 0) readonly buffer Tufts { vec4 tufts[]; };        // the patch's, 2 per tuft
layout(std430, binding = 5) buffer Command { uint command[5]; };           // DrawElementsIndirectCommand
layout(std430, binding = 6) writeonly buffer Visible { vec4 visible[]; };  // 5 per tuft

const int MAX_RUNS = 16;           // grass.c's GRASS_MAX_RUNS (the mesh's parts)
uniform uint u_tuft_count;         // the invocations: the tufts of the runs below
uniform int u_run_count;           // the runs of tufts looked at: those of the parts in view
uniform uint u_run_first[MAX_RUNS];        // each run's first tuft in the patch
uniform uint u_run_start[MAX_RUNS + 1];    // the invocations before each run
uniform vec3 u_offset;             // patch origin − camera
uniform float u_range;
uniform float u_height;
uniform vec4 u_planes[6];          // the view's frustum, camera-relative: dot(n, p) + d ≥ 0 inside
uniform vec2 u_camera_wave;        // the camera's x, z modulo the gusts' 256 m period
uniform vec3 u_player;             // the player's feet − camera; far away when nothing bends
uniform float u_time;

const vec2 WIND = vec2(0.8, 0.6);

// The top's offset from the root: up, leaning with the gusts, pushed away from the player.
vec3 tuft_top(vec3 root, vec3 up, float height, uint seed) {
    vec3 tip = up * height;
    // 12 and 9 waves over the 256 m period along x and z: a 17 m gust front along WIND that wraps
    // with the camera's position without a seam; each tuft adds its own flutter.
    vec2 world_xz = root.xz + u_camera_wave;
    float gust = sin(dot(world_xz, vec2(12.0, 9.0)) * (6.2831853 / 256.0) - u_time * 1.9) * 0.5 + 0.5;
    float flutter = sin(u_time * 3.1 + grass_unit(seed) * 6.2831853) * 0.35;
    tip.xz += WIND * (gust * 0.35 + flutter * 0.15) * height;
    // Bent away from the player's feet within about a metre and a half.
    vec3 away = root + tip - u_player;
    float reach = (1.0 - smoothstep(0.3, 1.5, length(away.xz))) * (1.0 - smoothstep(1.0, 2.0, abs(root.y - u_player.y)));
    vec2 outwards = length(away.xz) > 1e-3 ? normalize(away.xz) : vec2(1.0, 0.0);
    tip.xz += outwards * reach * height * 0.9;
    tip.y -= reach * height * 0.45;
    return tip;
}

void main() {
    uint t = gl_GlobalInvocationID.x;
    if (t >= u_tuft_count) return;
    int run = 0;
    while (run + 1 < u_run_count && t >= u_run_start[run + 1]) run++;
    t = u_run_first[run] + (t - u_run_start[run]);
    vec4 a = tufts[2u * t], b = tufts[2u * t + 1u];
    uint seed = floatBitsToUint(a.w);
    vec3 root = a.xyz + u_offset;
    float scale = grass_scale(seed, length(root), u_range);
    if (scale <= 0.0) return;
    // A sphere around the tuft, bent or swaying, must reach inside every plane.
    float height = grass_tuft_height(seed, b.w, scale, u_height);
    vec3 centre = root + vec3(0.0, 0.5 * height, 0.0);
    for (int p = 0; p < 6; p++)
        if (dot(u_planes[p].xyz, centre) + u_planes[p].w < -1.2 * height) return;
    vec3 normal = normalize(b.xyz);
    vec3 up = normalize(normal + vec3(0.0, 1.0, 0.0));
    float turn = grass_unit(grass_hash(seed ^ 0x1b56c4e9u)) * 3.14159265;
    vec3 across = vec3(cos(turn), 0.0, sin(turn)), beside = vec3(-across.z, 0.0, across.x);
    vec3 side0 = normalize(across - up * dot(across, up)) * 0.55 * height;
    vec3 side1 = normalize(beside - up * dot(beside, up)) * 0.55 * height;
    vec3 tint = mix(vec3(0.85, 0.92, 0.80), vec3(1.15, 1.08, 0.90), grass_unit(grass_hash(seed ^ 0x2c1b3c6du)));
    vec3 light = light_surface(tint, normal);
    float distance = length(root);
    float fog = 1.0 - exp(-distance * u_fog_density);                 // as common.glsl's apply_fog
    vec3 fog_color = sky_color(root / max(distance, 1e-4));
    uint slot = atomicAdd(command[1], 1u);
    visible[5u * slot] = vec4(root, fog);
    visible[5u * slot + 1u] = vec4(side0, light.r);
    visible[5u * slot + 2u] = vec4(side1, light.g);
    visible[5u * slot + 3u] = vec4(tuft_top(root, up, height, seed), light.b);
    visible[5u * slot + 4u] = vec4(fog_color, 0.0);
}
