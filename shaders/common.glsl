// common.glsl — lighting shared by the scene shaders: one sun, sky ambient, distance fog.

uniform vec3 u_sun_direction;      // towards the sun, normalised
uniform vec3 u_camera_position;
uniform float u_fog_density;       // per metre: 1 − e^(−distance·density) of the colour is fog

const vec3 SUN_COLOR = vec3(1.0, 0.95, 0.85);
const vec3 SKY_ZENITH = vec3(0.25, 0.45, 0.85);
const vec3 SKY_HORIZON = vec3(0.70, 0.80, 0.95);
const vec3 GROUND_BOUNCE = vec3(0.30, 0.27, 0.22);

vec3 sky_color(vec3 direction) {
    float up = clamp(direction.y, 0.0, 1.0);
    vec3 sky = mix(SKY_HORIZON, SKY_ZENITH, pow(up, 0.6));
    float sun = max(dot(direction, u_sun_direction), 0.0);
    sky += SUN_COLOR * (pow(sun, 600.0) * 4.0 + pow(sun, 8.0) * 0.15);
    return sky;
}

// Lambert sun, of which the share `sun_visibility` arrives (shadow.glsl: 0 in shadow), plus a
// hemisphere ambient (sky above, warm bounce below) that shadows leave alone.
vec3 light_surface_shadowed(vec3 albedo, vec3 normal, float sun_visibility) {
    float diffuse = max(dot(normal, u_sun_direction), 0.0) * sun_visibility;
    vec3 ambient = mix(GROUND_BOUNCE, SKY_ZENITH, normal.y * 0.5 + 0.5) * 0.35;
    return albedo * (SUN_COLOR * diffuse + ambient);
}

vec3 light_surface(vec3 albedo, vec3 normal) { return light_surface_shadowed(albedo, normal, 1.0); }

vec3 apply_fog(vec3 color, vec3 world_position) {
    vec3 to_point = world_position - u_camera_position;
    float distance = length(to_point);
    float fog = 1.0 - exp(-distance * u_fog_density);
    return mix(color, sky_color(to_point / max(distance, 1e-4)), fog);
}
