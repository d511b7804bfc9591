// Provides transmitted_light(x, frame, wo): the light a transmissive glTF surface (KHR_materials_transmission,
// KHR_materials_volume) lets through, read from the frame drawn before it (forward.py's see-through draws copy
// colour and depth into u_behind / u_behind_depth first) — the screen-space transmission of three.js and
// Filament, with a blur set by the lobe instead of by the roughness alone:
// - thin-walled: the pixel behind the fragment, unbent;
// - a volume: the view ray refracted by the ior and carried the thickness (x the mesh's scale) through the
//   volume, the pixel where it comes out, attenuated by Beer-Lambert over that length and by the exit's Fresnel at
//   normal incidence; it is not refracted again where it leaves (three.js' approximation; the reference follows
//   the real path: docs/assets.md measures both).
// The mip level: the transmitted lobe's width (TRANSMISSION_SPREAD x alpha radians) times the distance from the
// surface to what the depth copy holds behind it, in pixels.
#if defined(BRDF_GLTF_TRANSMISSION) && BRDF_GLTF_TRANSMISSION
uniform sampler2D u_behind;
uniform sampler2D u_behind_depth;  // reversed-Z (gpu/depth.py)
uniform mat4 u_view_proj;
uniform mat4 u_inv_view_proj;
uniform float u_thickness_scale;   // world units per mesh unit (the mesh's transform)

#define TRANSMISSION_SPREAD 5.0

vec2 screen_of(vec3 p) {
    vec4 clip = u_view_proj * vec4(p, 1.0);
    return clip.xy / clip.w * 0.5 + 0.5;
}

vec3 transmitted_light(vec3 x, mat3 frame, vec3 wo) {
    vec3 v = frame * wo;
    float alpha;
    vec3 weight = material_transmission(frame, v, alpha);
    vec3 exit = x;
#if BRDF_GLTF_TRANSMISSION == 2
    vec3 dir = refract(-v, frame[2], 1.0 / m_transmission.z);
    float travel = g_thickness * u_thickness_scale;
    exit = x + dir * travel;
    weight *= exp(-m_absorption * travel) * (1.0 - m_dielectric_f0);  // and leaving: the Fresnel at normal incidence
#endif
    vec2 uv = screen_of(exit);
    vec2 size = vec2(textureSize(u_behind, 0));
    float depth = max(textureLod(u_behind_depth, uv, 0.0).r, 1e-7);  // the background: far, not infinite
    vec4 behind = u_inv_view_proj * vec4(uv * 2.0 - 1.0, depth, 1.0);
    vec3 p = behind.xyz / behind.w;
    vec3 gap = p - exit;
    float radius = TRANSMISSION_SPREAD * alpha * length(gap);  // the lobe's footprint there, world units
    vec3 across = cross(gap, abs(gap.y) < 0.9 * length(gap) ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0));
    float pixels = radius > 0.0 ? length((screen_of(p + radius * normalize(across)) - screen_of(p)) * size) : 0.0;
    float lod = log2(max(pixels, 1e-3));
    return weight * textureLod(u_behind, uv, lod).rgb;
}
#endif
