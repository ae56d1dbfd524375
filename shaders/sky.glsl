// sky.glsl — the clouds of the sky (002 §4.2's sky dome: noise clouds over the scene; here the
// noise is evaluated per pixel on a plane above the world instead of a texture, so there is no
// seam or pole to hide). Shared by sky.frag and water.frag, whose reflections show the same sky.
// Needs common.glsl (u_sun_direction) included first.

uniform float u_cloud_cover;       // 0 = clear sky (no clouds at all), 1 = overcast
uniform float u_time;              // seconds: the clouds drift with it

float cloud_hash(vec2 p) {
    p = fract(p * vec2(0.1031, 0.1030));
    p += dot(p, p.yx + 33.33);
    return fract((p.x + p.y) * p.x);
}

float cloud_noise(vec2 p) {
    vec2 i = floor(p), f = fract(p);
    f = f * f * (3.0 - 2.0 * f);
    float a = cloud_hash(i), b = cloud_hash(i + vec2(1, 0));
    float c = cloud_hash(i + vec2(0, 1)), d = cloud_hash(i + vec2(1, 1));
    return mix(mix(a, b, f.x), mix(c, d, f.x), f.y);
}

float cloud_fbm(vec2 p, int octaves) {
    float sum = 0.0, amplitude = 0.5;
    for (int octave = 0; octave < octaves; octave++) {
        sum += amplitude * cloud_noise(p);
        p = p * 2.03 + vec2(17.1, 9.2);
        amplitude *= 0.5;
    }
    return sum;
}

// `octaves` of the clouds' noise: 5 in the sky; fewer where they are seen through moving
// water, whose waves hide the finest ones.
vec3 add_clouds(vec3 sky, vec3 direction, int octaves) {
    if (u_cloud_cover <= 0.0 || direction.y <= 0.01) return sky;
    // Where the ray meets a cloud plane 1 km up, in kilometres, moved by a steady wind.
    vec2 plane = direction.xz / direction.y + vec2(0.012, 0.004) * u_time;
    float density = cloud_fbm(plane * 1.5, octaves);
    float cover = smoothstep(1.0 - u_cloud_cover, 1.05 - u_cloud_cover * 0.6, density);
    // Thin out towards the horizon, where the plane's far cells would alias.
    cover *= smoothstep(0.02, 0.25, direction.y);
    float lit = 0.75 + 0.25 * max(dot(u_sun_direction, vec3(0, 1, 0)), 0.0);
    vec3 cloud = mix(vec3(0.78, 0.80, 0.85), vec3(1.0), density) * lit;
    return mix(sky, cloud, cover * 0.9);
}

// The sky along a unit direction, clouds included (`octaves` of their noise, 5 for the sky).
vec3 sky_with_clouds(vec3 direction, int octaves) { return add_clouds(sky_color(direction), direction, octaves); }
