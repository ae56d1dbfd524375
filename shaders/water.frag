#version 450 core
// water.frag — a water surface over the opaque frame (002 §3.4, 004 §4.3). Refraction: the
// frame under the water (u_scene_color, u_scene_depth) at a position moved by a dudv map, masked
// by depth: where the scene at the moved position is nearer than the surface (something above
// the water), the unmoved position is used instead, so nothing above the water leaks in and the
// shore has no halo (godot-proposals #6025). Reflection: the sky along the reflected ray, or a
// pass of its own (u_reflection, the view mirrored about the plane, its image upside down), and
// the sun's highlight on a scrolling normal map. A Schlick Fresnel term blends the two. The
// water's thickness along the view ray sets the colour (Beer–Lambert: shallow clear, thick dark
// and green); its depth under the surface sets, as 004 §4.3 asks, the bumps' strength and the
// reflectivity, and fades the surface out towards the shore, where it goes to zero (no hard
// line; Crest #10, #262).
// Low quality (u_blend) reads nothing of the frame: on a software rasteriser a read waits until
// the whole frame is drawn. The surface is blended over the frame instead (dual-source: the
// water's own light added, the frame under it scaled per channel), the depth under the surface
// from the far terrain's heights (water_ground.glsl), so the bottom shows through undistorted.

#include "common.glsl"
#include "sky.glsl"
#include "water.glsl"
#include "water_ground.glsl"

// The depth test before the shader: the sea behind hills costs nothing. Water writes no depth,
// so the row mask's discard loses nothing by it.
layout(early_fragment_tests) in;

in vec3 v_relative_position;
in vec2 v_cell;

uniform sampler2D u_scene_color;
uniform sampler2D u_reflection;
uniform sampler2D u_dudv;          // RG: a tileable distortion in [−1, 1] (0.5 + 0.5·d)
uniform sampler2D u_normals;       // RG: a tileable normal's x and z (0.5 + 0.5·n)
uniform int u_use_reflection;      // 1: u_reflection holds the mirrored view (high)
uniform vec2 u_screen_size;        // pixels of the frame
uniform vec2 u_texture_offset;     // camera x, z modulo the maps' common period
uniform int u_under;               // 1: the camera is below this surface
uniform int u_blend;               // 1: low, blended over the frame, none of it read
uniform float u_camera_y;          // world height of the camera (the ground's heights are world's)
uniform int u_use_rows;            // 1: cells outside u_rows are no water (lakes)
uniform uint u_rows[32];           // bit i of u_rows[k]: cell (i, k) holds this water

layout(location = 0, index = 0) out vec4 frag_color;
layout(location = 0, index = 1) out vec4 frag_factor;   // low: what the frame under is kept by

// Repeats (terrain_water.c's WATER_MAP_PERIOD, 120 m, is a multiple of each): normals 8 and 20 m,
// dudv 12 and 10 m.
const float WAVE_METRES = 8.0, WAVE2_METRES = 20.0;
const float DUDV_METRES = 12.0, DUDV2_METRES = 10.0;
const float DISTORTION = 0.025;    // screen share the refraction moves at most, close up
// Depths are vertical (the bottom seen through this pixel under the surface), so the shore's
// width on the ground does not shrink at grazing angles, where the water along the ray grows
// fastest.
const float SHORE_METRES = 0.5;    // depth over which the surface fades in from the waterline
const float SHALLOW_METRES = 0.6;  // scale of "shallow" for bumps and reflectivity

// Two layers of the normal map scrolling in different directions; `strength` scales the slopes.
vec3 wave_normal(vec2 world, float strength) {
    vec2 a = texture(u_normals, world / WAVE_METRES + vec2(0.030, 0.020) * u_time).rg * 2.0 - 1.0;
    vec2 b = texture(u_normals, world / WAVE2_METRES + vec2(-0.017, 0.026) * u_time).rg * 2.0 - 1.0;
    vec2 slope = (a + b) * 0.5 * strength;
    return normalize(vec3(slope.x, 1.0, slope.y));
}

vec2 wave_dudv(vec2 world) {
    vec2 a = texture(u_dudv, world / DUDV_METRES + vec2(0.020, 0.004) * u_time).rg * 2.0 - 1.0;
    vec2 b = texture(u_dudv, world / DUDV2_METRES + vec2(-0.008, 0.015) * u_time).rg * 2.0 - 1.0;
    return (a + b) * 0.5;
}

// Whether the cell or one of its eight neighbours holds this water. The mask is cells' tops; the
// ground's mesh, smoothed by the field's kernel, may dip under the surface a little past them,
// and a coarse level's cells straddle the waterline: one cell more lets the depth test and the
// shore's fade draw the waterline there instead of the mask's square edge.
bool near_plane_cells(ivec2 cell) {
    for (int k = max(cell.y - 1, 0); k <= min(cell.y + 1, 31); k++) {
        uint row = u_rows[k];
        for (int i = max(cell.x - 1, 0); i <= min(cell.x + 1, 31); i++)
            if (((row >> uint(i)) & 1u) != 0u) return true;
    }
    return false;
}

vec2 clamp_uv(vec2 uv) { return clamp(uv, 0.5 / u_screen_size, 1.0 - 0.5 / u_screen_size); }

// The surface from below: through it, the frame above the water (bent a little); past the
// critical angle (sin θt = n·sin θi ≥ 1) total internal reflection shows the water's own dark
// colour; a darker look throughout.
vec4 seen_from_below(vec3 view_dir, vec2 uv, vec2 world) {
    vec3 normal = -wave_normal(world, 0.5);
    float cos_i = clamp(dot(-view_dir, normal), 0.0, 1.0);
    float sin_t = WATER_IOR * sqrt(1.0 - cos_i * cos_i);
    vec3 inside = water_body_color() * 0.6;
    if (sin_t >= 1.0) return vec4(inside, 1.0);
    float cos_t = sqrt(1.0 - sin_t * sin_t);
    vec3 through = texture(u_scene_color, clamp_uv(uv + wave_dudv(world) * DISTORTION * 0.5)).rgb;
    return vec4(mix(through * 0.75, inside, water_fresnel(cos_t)), 1.0);
}

// Low: with the frame's colour D under the surface, medium's colour is D·T·(1 − R) + own, with
// T the transmittance, R the reflectance and own = body·(1 − T)·(1 − R) + sky·R. Dual-source
// blending (ONE, SRC1_COLOR) forms exactly that, per channel, without reading D: frag_color
// is own and frag_factor is T·(1 − R), both through the fog (apply_fog mixes linearly) and the
// shore's fade, which mixes towards D.
vec4 blended_over_frame(vec3 view_dir, float surface_distance, vec2 world, out vec4 factor) {
    float ground;
    // Deep where no far terrain level reaches (past its outermost level, the far plane's fade).
    bool known = ground_height(v_relative_position.xz, ground);
    float depth = known ? max(v_relative_position.y + u_camera_y - ground, 0.0) : 1e3;
    float thickness = depth / max(-view_dir.y, 1e-3);
    float deep = 1.0 - exp(-depth / SHALLOW_METRES);
    vec3 normal = wave_normal(world, mix(0.15, 1.0, deep) / (1.0 + surface_distance / 60.0));
    vec3 transmittance = exp(-WATER_EXTINCTION * thickness);
    vec3 reflected_dir = reflect(view_dir, normal);
    reflected_dir.y = abs(reflected_dir.y);
    float fresnel = water_fresnel(dot(-view_dir, normal)) * mix(0.4, 1.0, deep);
    vec3 own = water_body_color() * (1.0 - transmittance) * (1.0 - fresnel) + sky_with_clouds(reflected_dir, 3) * fresnel;
    own += SUN_COLOR * pow(max(dot(reflected_dir, u_sun_direction), 0.0), 400.0) * 4.0 * deep;
    vec3 fog_color = apply_fog(vec3(0.0), v_relative_position);
    vec3 clear = apply_fog(vec3(1.0), v_relative_position) - fog_color;     // 1 − the fog's share
    float shore = smoothstep(0.0, SHORE_METRES, depth);
    factor = vec4(1.0 - shore + shore * transmittance * (1.0 - fresnel) * clear, 1.0);
    return vec4(shore * (own * clear + fog_color), 1.0);
}

void main() {
    frag_factor = vec4(0.0);             // only low's blending reads it
    if (u_use_rows != 0 && !near_plane_cells(ivec2(floor(v_cell)))) discard;
    float surface_distance = length(v_relative_position);
    vec3 view_dir = v_relative_position / max(surface_distance, 1e-4);
    vec2 uv = gl_FragCoord.xy / u_screen_size;
    vec2 world = v_relative_position.xz + u_texture_offset;
    if (u_under != 0) {
        frag_color = seen_from_below(view_dir, uv, world);
        return;
    }
    if (u_blend != 0) {
        vec4 factor;
        frag_color = blended_over_frame(view_dir, surface_distance, world, factor);
        frag_factor = factor;
        return;
    }
    // The water straight behind the surface; this fragment passed the depth test, so the scene
    // there lies behind it (to the depth buffer's precision).
    float straight = max(scene_distance(uv) - surface_distance, 0.0);
    float depth = straight * max(-view_dir.y, 0.0);
    float deep = 1.0 - exp(-depth / SHALLOW_METRES);              // 0 at the shore, → 1 deep
    // Far away the waves are smaller than a pixel and the surface reads as smooth.
    vec3 normal = wave_normal(world, mix(0.15, 1.0, deep) / (1.0 + surface_distance / 60.0));
    // Distortion shrinks with distance (the waves' size on screen) and towards the shore.
    vec2 offset = wave_dudv(world) * DISTORTION * deep / (1.0 + surface_distance * 0.05);
    vec2 bent_uv = clamp_uv(uv + offset);
    float bent = scene_distance(bent_uv);
    if (bent < surface_distance) {                                // the depth mask
        bent_uv = uv;
        bent = surface_distance + straight;
    }
    float thickness = max(bent - surface_distance, 0.0);
    vec3 transmittance = exp(-WATER_EXTINCTION * thickness);
    vec3 refracted = texture(u_scene_color, bent_uv).rgb * transmittance + water_body_color() * (1.0 - transmittance);

    vec3 reflected_dir = reflect(view_dir, normal);
    reflected_dir.y = abs(reflected_dir.y);                        // a wave never mirrors the ground
    vec3 reflected = u_use_reflection != 0 ? texture(u_reflection, clamp_uv(vec2(uv.x, 1.0 - uv.y) + offset)).rgb
                                           : sky_with_clouds(reflected_dir, 3);
    float fresnel = water_fresnel(dot(-view_dir, normal)) * mix(0.4, 1.0, deep);
    vec3 color = mix(refracted, reflected, fresnel);
    float highlight = pow(max(dot(reflected_dir, u_sun_direction), 0.0), 400.0) * 4.0;
    color += SUN_COLOR * highlight * deep;
    color = apply_fog(color, v_relative_position);
    frag_color = vec4(color, smoothstep(0.0, SHORE_METRES, depth));
}
