// shadow.glsl — the sun's cascaded shadow map, read by the surfaces that receive it (terrain,
// clipmap). terrain_shadow.c fits the cascades and renders them (shadow.vert, shadow.frag);
// this side picks the cascade of the point's slice of the view and filters the comparison.

uniform sampler2DArrayShadow u_shadow_map;  // one layer per cascade, compare mode on
uniform int u_shadow_cascades;              // 0 = no shadows (quality off)
uniform mat4 u_shadow_matrix[4];            // camera-relative position → (u, v, depth) in [0, 1]
uniform float u_shadow_normal_offset[4];    // metres along the normal: a few texels of the cascade
uniform float u_shadow_splits[4];           // where each cascade's slice of the view ends, metres
uniform vec3 u_shadow_forward;              // the view's axis (slices are depths along it)
uniform float u_shadow_texel;               // 1 / map size
uniform int u_shadow_taps;                  // PCF: taps² bilinear comparisons, a texel apart

// The share of the sun that reaches `relative_position` (camera-relative, metres) on a surface
// of unit normal `normal`: 1 lit, 0 in shadow. Straight-line code, no loop over the cascades:
// llvmpipe runs every pixel of a block through every branch any of them takes.
float shadow_visibility(vec3 relative_position, vec3 normal) {
    // Faces turned from the sun get no direct light to hide: skip the lookups.
    if (u_shadow_cascades == 0 || dot(normal, u_sun_direction) <= 0.0) return 1.0;
    // The cascade of the point's slice: its casters were culled against that slice.
    float depth = dot(relative_position, u_shadow_forward);
    int last = u_shadow_cascades - 1;
    if (depth > u_shadow_splits[last]) return 1.0;
    int c = int(depth > u_shadow_splits[0]) + int(last > 1 && depth > u_shadow_splits[1]);
    // Normal offset: the lookup moves off the surface by about a texel of this cascade, so
    // near the terminator, where the faces that cast meet those that receive, a surface does
    // not compare against its own rasterised depth (acne); the map's faces are those turned
    // from the sun (terrain_shadow.c), so a lit face never meets its own.
    vec3 p = relative_position + normal * u_shadow_normal_offset[c];
    vec3 s = (u_shadow_matrix[c] * vec4(p, 1.0)).xyz;
    vec2 edge = abs(s.xy - 0.5);
    if (max(edge.x, edge.y) > 0.5 - float(u_shadow_taps + 1) * u_shadow_texel || s.z > 1.0) return 1.0;
    // Each tap is a bilinear 2 × 2 comparison (GL_LINEAR on a shadow sampler).
    float lit;
    if (u_shadow_taps == 1) {
        lit = texture(u_shadow_map, vec4(s.xy, float(c), s.z));
    } else {
        lit = 0.0;
        float half_span = 0.5 * float(u_shadow_taps - 1);
        for (int y = 0; y < u_shadow_taps; y++)
            for (int x = 0; x < u_shadow_taps; x++)
                lit += texture(u_shadow_map, vec4(s.xy + (vec2(x, y) - half_span) * u_shadow_texel, float(c), s.z));
        lit /= float(u_shadow_taps * u_shadow_taps);
    }
    // The last cascade fades out over the end of its slice: no line where the shadows end.
    if (c == last) lit = mix(lit, 1.0, smoothstep(0.8 * u_shadow_splits[c], u_shadow_splits[c], depth));
    return lit;
}
