// water_optics.glsl — the water's optics (002 §3.4, 004 §4.3), shared by the water surfaces
// (water.frag, water_under.frag through water.glsl) and the far terrain's lakes (clipmap.frag).
// Needs common.glsl's u_sun_direction.

const float WATER_IOR = 1.33;
const float WATER_F0 = 0.02;               // ((n − 1)/(n + 1))² at normal incidence, n = 1.33
// Beer–Lambert extinction per metre of water: red goes first, green lasts longest, so thick
// water turns dark blue-green and a metre of it leaves at least three quarters of each channel.
const vec3 WATER_EXTINCTION = vec3(0.28, 0.055, 0.075);
const vec3 WATER_BODY = vec3(0.025, 0.15, 0.13);   // what thick water scatters back, lit by the sun
const vec3 WATER_FOG = vec3(0.05, 0.26, 0.28);     // the colour of distance seen under water

// The light the water body scatters: the sun from above and the sky's ambient.
vec3 water_body_color() { return WATER_BODY * (0.35 + 0.65 * max(u_sun_direction.y, 0.0)); }

// Schlick's approximation of the Fresnel reflectance for a cosine on the air side.
float water_fresnel(float cosine) { return WATER_F0 + (1.0 - WATER_F0) * pow(1.0 - clamp(cosine, 0.0, 1.0), 5.0); }
