// Provides brdf_eval(wo, wi) for glTF 2.0's metallic-roughness material (twin of reflets/brdf/gltf.py), and the
// per-fragment hooks a textured material offers every shading pass (forward.frag, arealight.frag, lights.glsl):
// material_surface(uvs, frame) reads the textures (uvs: the two uv sets in xy and zw) into the parameters brdf_eval
// uses and applies the normal map;
// material_emission(), material_occlusion(), material_coverage(), material_ibl(mu, ...). Layers: the sheen
// (BRDF_GLTF_SHEEN) over the base, the clear coat (BRDF_GLTF_COAT) over both.
#define MATERIAL_SURFACE 1
#define MATERIAL_IBL 1

uniform vec4 m_base_color;           // linear RGBA factor
uniform vec2 m_metallic_roughness;   // factors
uniform float m_normal_scale;
uniform float m_occlusion_strength;
uniform vec3 m_emissive;             // factor x emissive_strength
uniform float m_alpha_cutoff;
uniform float m_dielectric_f0;       // ((ior - 1) / (ior + 1))^2: 0.04 at glTF's 1.5 (KHR_materials_ior)
uniform vec4 m_specular;             // KHR_materials_specular: Fresnel tint (RGB) and weight
#if BRDF_GLTF_SPECULAR_MAP
uniform sampler2D m_specular_map;
uniform mat3 m_specular_map_uv;
#endif
#if BRDF_GLTF_SPECULAR_COLOR_MAP
uniform sampler2D m_specular_color_map;
uniform mat3 m_specular_color_map_uv;
#endif
// each texture with the mat3 taking mesh uv (v up) to image uv (origin top-left, KHR_texture_transform applied)
#if BRDF_GLTF_BASE_MAP
uniform sampler2D m_base_color_map;
uniform mat3 m_base_color_map_uv;
#endif
#if BRDF_GLTF_MR_MAP
uniform sampler2D m_metallic_roughness_map;
uniform mat3 m_metallic_roughness_map_uv;
#endif
#if BRDF_GLTF_NORMAL_MAP
uniform sampler2D m_normal_map;
uniform mat3 m_normal_map_uv;
#endif
#if BRDF_GLTF_OCCLUSION_MAP
uniform sampler2D m_occlusion_map;
uniform mat3 m_occlusion_map_uv;
#endif
#if BRDF_GLTF_EMISSIVE_MAP
uniform sampler2D m_emissive_map;
uniform mat3 m_emissive_map_uv;
#endif
#if BRDF_GLTF_COAT
#define MATERIAL_COAT 1
uniform vec2 m_clearcoat;            // KHR_materials_clearcoat: weight and roughness factors
uniform float m_clearcoat_normal_scale;
#endif
#if BRDF_GLTF_COAT_MAP
uniform sampler2D m_clearcoat_map;
uniform mat3 m_clearcoat_map_uv;
#endif
#if BRDF_GLTF_COAT_ROUGHNESS_MAP
uniform sampler2D m_clearcoat_roughness_map;
uniform mat3 m_clearcoat_roughness_map_uv;
#endif
#if BRDF_GLTF_COAT_NORMAL_MAP
uniform sampler2D m_clearcoat_normal_map;
uniform mat3 m_clearcoat_normal_map_uv;
#endif
#if BRDF_GLTF_SHEEN
uniform vec4 m_sheen;                // KHR_materials_sheen: colour and roughness factors
#endif
#if BRDF_GLTF_SHEEN_MAP
uniform sampler2D m_sheen_color_map;
uniform mat3 m_sheen_color_map_uv;
#endif
#if BRDF_GLTF_SHEEN_ROUGHNESS_MAP
uniform sampler2D m_sheen_roughness_map;
uniform mat3 m_sheen_roughness_map_uv;
#endif
#if BRDF_GLTF_ANISOTROPY
uniform vec3 m_anisotropy;           // KHR_materials_anisotropy: (cos, sin) of the rotation, strength
#endif
#if BRDF_GLTF_ANISOTROPY_MAP
uniform sampler2D m_anisotropy_map;
uniform mat3 m_anisotropy_map_uv;
#endif
// the split sum's table of this BRDF (reflets/brdf/gltf.py, ibl_table): (A, B, P, E_sheen) at (mu, roughness)
#if BRDF_GLTF_TRANSMISSION
uniform vec3 m_transmission;         // KHR_materials_transmission's factor, KHR_materials_volume's thickness, ior
uniform vec3 m_absorption;           // the volume's sigma (per world unit): -ln(attenuation colour) / distance
#endif
#if BRDF_GLTF_TRANSMISSION_MAP
uniform sampler2D m_transmission_map;
uniform mat3 m_transmission_map_uv;
#endif
#if BRDF_GLTF_THICKNESS_MAP
uniform sampler2D m_thickness_map;
uniform mat3 m_thickness_map_uv;
#endif
uniform sampler2D m_ibl_lut;

// The table read bilinearly in float (clamped to its edges, texel centres at (i + 0.5) / size: the sampler's own
// rule): a GPU's filtering weights may have 8 bits (NVIDIA's), which put E_sheen 40 % off where 1 - E nears 0.
vec4 ibl_table(vec2 uv) {
    ivec2 size = textureSize(m_ibl_lut, 0);
    vec2 p = clamp(uv * vec2(size) - 0.5, vec2(0.0), vec2(size - 1));
    ivec2 i = ivec2(floor(p));
    ivec2 j = min(i + 1, size - 1);
    vec2 f = p - vec2(i);
    return mix(mix(texelFetch(m_ibl_lut, i, 0), texelFetch(m_ibl_lut, ivec2(j.x, i.y), 0), f.x),
               mix(texelFetch(m_ibl_lut, ivec2(i.x, j.y), 0), texelFetch(m_ibl_lut, j, 0), f.x), f.y);
}

// the parameters at this fragment (material_surface sets them)
vec3 g_base = vec3(1.0);
float g_metallic = 1.0;
float g_alpha = 1.0;
float g_coverage = 1.0;
float g_occlusion = 1.0;
vec3 g_emission = vec3(0.0);
float g_coat = 0.0;                  // the clear coat: weight, alpha, normal in the shading frame
float g_coat_alpha = 1.0;
vec3 g_coat_n = vec3(0.0, 0.0, 1.0);
float g_coat_normal_variance = 0.0;
float g_normal_variance = 0.0;  // of the normal map under the footprint (Toksvig), added to alpha^2
vec3 g_f0 = vec3(0.04);              // the dielectric's Fresnel at normal incidence and its weight
float g_specular = 1.0;
vec3 g_sheen = vec3(0.0);            // the sheen: colour and roughness (at least 0.07, as gltf.py)
float g_sheen_roughness = 0.07;
vec3 g_anisotropy = vec3(1.0, 0.0, 0.0);  // the lobe's direction (cos, sin) in the shading frame, strength^2
float g_transmission = 0.0;          // the share of the diffuse lobe transmitted, and the volume's thickness
float g_thickness = 0.0;

vec4 gltf_texel(sampler2D map, mat3 to_image, vec2 uv) {
    return texture(map, (to_image * vec3(uv, 1.0)).xy);
}

// a slot's texture coordinates: its flag is 1 + its uv set (gltf.py's flags)
#define GLTF_UV(flag) ((flag) == 2 ? uvs.zw : uvs.xy)

void material_surface(vec4 uvs, inout mat3 frame) {
#if BRDF_GLTF_COAT
    // the coat's normal: the geometric one (frame is still unmapped here), or its own normal map on it
    vec3 coat_world = frame[2];
#if BRDF_GLTF_COAT_NORMAL_MAP
    vec3 coat_local = gltf_texel(m_clearcoat_normal_map, m_clearcoat_normal_map_uv, GLTF_UV(BRDF_GLTF_COAT_NORMAL_MAP)).xyz * 2.0 - 1.0;
    float coat_length = clamp(length(coat_local), 1e-3, 1.0);  // Toksvig, as for the base's normal map
    g_coat_normal_variance = 2.0 * (1.0 - coat_length) / coat_length * m_clearcoat_normal_scale * m_clearcoat_normal_scale;
    coat_local.xy *= m_clearcoat_normal_scale;
    coat_world = normalize(frame * coat_local);
#endif
    g_coat = m_clearcoat.x;
#if BRDF_GLTF_COAT_MAP
    g_coat *= gltf_texel(m_clearcoat_map, m_clearcoat_map_uv, GLTF_UV(BRDF_GLTF_COAT_MAP)).r;
#endif
    float coat_roughness = m_clearcoat.y;
#if BRDF_GLTF_COAT_ROUGHNESS_MAP
    coat_roughness *= gltf_texel(m_clearcoat_roughness_map, m_clearcoat_roughness_map_uv, GLTF_UV(BRDF_GLTF_COAT_ROUGHNESS_MAP)).g;
#endif
    g_coat_alpha = max(coat_roughness * coat_roughness, 1e-3);
#endif
    vec4 base = m_base_color;
#if BRDF_GLTF_BASE_MAP
    base *= gltf_texel(m_base_color_map, m_base_color_map_uv, GLTF_UV(BRDF_GLTF_BASE_MAP));
#endif
    g_base = base.rgb;
    g_coverage = base.a;
    vec2 mr = m_metallic_roughness;
#if BRDF_GLTF_MR_MAP
    mr *= gltf_texel(m_metallic_roughness_map, m_metallic_roughness_map_uv, GLTF_UV(BRDF_GLTF_MR_MAP)).bg;
#endif
    g_metallic = mr.x;
    g_alpha = max(mr.y * mr.y, 1e-3);
    g_specular = m_specular.a;
#if BRDF_GLTF_SPECULAR_MAP
    g_specular *= gltf_texel(m_specular_map, m_specular_map_uv, GLTF_UV(BRDF_GLTF_SPECULAR_MAP)).a;
#endif
    vec3 tint = m_specular.rgb;
#if BRDF_GLTF_SPECULAR_COLOR_MAP
    tint *= gltf_texel(m_specular_color_map, m_specular_color_map_uv, GLTF_UV(BRDF_GLTF_SPECULAR_COLOR_MAP)).rgb;
#endif
    g_f0 = min(m_dielectric_f0 * tint, vec3(1.0));
    g_occlusion = 1.0;
#if BRDF_GLTF_OCCLUSION_MAP
    g_occlusion = 1.0 + m_occlusion_strength * (gltf_texel(m_occlusion_map, m_occlusion_map_uv, GLTF_UV(BRDF_GLTF_OCCLUSION_MAP)).r - 1.0);
#endif
    g_emission = m_emissive;
#if BRDF_GLTF_EMISSIVE_MAP
    g_emission *= gltf_texel(m_emissive_map, m_emissive_map_uv, GLTF_UV(BRDF_GLTF_EMISSIVE_MAP)).rgb;
#endif
#if BRDF_GLTF_NORMAL_MAP
    vec3 local = gltf_texel(m_normal_map, m_normal_map_uv, GLTF_UV(BRDF_GLTF_NORMAL_MAP)).xyz * 2.0 - 1.0;
    // Toksvig: the mips hold means of unit normals; a mean shorter than 1 says how much the normals under this
    // fragment's footprint vary (the slope variance per axis is about 1 - |mean|): the lobe widens by it
    float mean_length = clamp(length(local), 1e-3, 1.0);
    g_normal_variance = 2.0 * (1.0 - mean_length) / mean_length * m_normal_scale * m_normal_scale;
    local.xy *= m_normal_scale;
    frame = normal_mapped_frame(frame, local);
#endif
#if BRDF_GLTF_COAT
    g_coat_n = normalize(transpose(frame) * coat_world);
#endif
#if BRDF_GLTF_SHEEN
    g_sheen = m_sheen.rgb;
    g_sheen_roughness = m_sheen.a;
#if BRDF_GLTF_SHEEN_MAP
    g_sheen *= gltf_texel(m_sheen_color_map, m_sheen_color_map_uv, GLTF_UV(BRDF_GLTF_SHEEN_MAP)).rgb;
#endif
#if BRDF_GLTF_SHEEN_ROUGHNESS_MAP
    g_sheen_roughness *= gltf_texel(m_sheen_roughness_map, m_sheen_roughness_map_uv, GLTF_UV(BRDF_GLTF_SHEEN_ROUGHNESS_MAP)).a;
#endif
    g_sheen_roughness = max(g_sheen_roughness, 0.07);
#endif
#if BRDF_GLTF_ANISOTROPY
    vec2 direction = vec2(1.0, 0.0);
    float strength = m_anisotropy.z;
#if BRDF_GLTF_ANISOTROPY_MAP
    vec3 texel = gltf_texel(m_anisotropy_map, m_anisotropy_map_uv, GLTF_UV(BRDF_GLTF_ANISOTROPY_MAP)).rgb;
    direction = texel.rg * 2.0 - 1.0;
    strength *= texel.b;
#endif
    direction = mat2(m_anisotropy.x, m_anisotropy.y, -m_anisotropy.y, m_anisotropy.x) * direction;  // turned
    float length_ = length(direction);
    g_anisotropy = vec3(length_ > 1e-6 ? direction / length_ : vec2(1.0, 0.0), strength * strength);
#endif
#if BRDF_GLTF_TRANSMISSION
    g_transmission = m_transmission.x;
#if BRDF_GLTF_TRANSMISSION_MAP
    g_transmission *= gltf_texel(m_transmission_map, m_transmission_map_uv, GLTF_UV(BRDF_GLTF_TRANSMISSION_MAP)).r;
#endif
    g_thickness = m_transmission.y;
#if BRDF_GLTF_THICKNESS_MAP
    g_thickness *= gltf_texel(m_thickness_map, m_thickness_map_uv, GLTF_UV(BRDF_GLTF_THICKNESS_MAP)).g;
#endif
#endif
}

#if BRDF_GLTF_SHEEN
// the sheen lobe's albedo E at mu = n.v (the table's fourth channel, at the sheen roughness: gltf.py's
// sheen_albedo interpolates the same texels)
float gltf_sheen_albedo(float mu) {
    return ibl_table(vec2(clamp(mu, 0.0, 1.0), g_sheen_roughness)).a;
}

// KHR_materials_sheen's fitted exponent of the Charlie lambda, and lambda itself
float gltf_sheen_l(float x, float alpha) {
    float t = (1.0 - alpha) * (1.0 - alpha);
    float a = mix(21.5473, 25.3245, t), b = mix(3.82987, 3.32435, t), c = mix(0.19823, 0.16801, t);
    float d = mix(-1.97760, -1.27393, t), e = mix(-4.32054, -4.85967, t);
    return a / (1.0 + b * pow(abs(x), c)) + d * x + e;
}
float gltf_sheen_lambda(float mu, float alpha) {
    return abs(mu) < 0.5 ? exp(gltf_sheen_l(mu, alpha)) : exp(2.0 * gltf_sheen_l(0.5, alpha) - gltf_sheen_l(1.0 - mu, alpha));
}

// C D_s V_s + f min(1 - max(C) E(n.v), 1 - max(C) E(n.l)) (gltf.py's module docstring; wo, wi above the surface)
vec3 gltf_sheened(vec3 f, vec3 wo, vec3 wi, vec3 h) {
    float alpha = g_sheen_roughness * g_sheen_roughness;
    float peak = max(g_sheen.r, max(g_sheen.g, g_sheen.b));
    float scaling = max(min(1.0 - peak * gltf_sheen_albedo(wo.z), 1.0 - peak * gltf_sheen_albedo(wi.z)), 0.0);
    float sin2 = clamp(1.0 - h.z * h.z, 0.0, 1.0);
    float d = (2.0 + 1.0 / alpha) * pow(sin2, 0.5 / alpha) / (2.0 * PI);
    float v = 1.0 / ((1.0 + gltf_sheen_lambda(wo.z, alpha) + gltf_sheen_lambda(wi.z, alpha)) * (4.0 * wo.z * wi.z));
    return g_sheen * (d * v) + f * scaling;
}
#endif

// Specular anti-aliasing: a pixel averages the lobe over the normals its footprint spans. On a near-mirror
// (roughness 0: alpha = 1e-3) a point light's highlight is a sub-pixel needle that a few samples per pixel hit or
// miss, so alpha^2 grows by (1) the screen-space variance of the geometric normal n (Kaplanyan, Hill, Patney &
// Lefohn 2016, as Filament does it, with its constants: sigma^2 = 0.15, at most 0.2) and (2) the normal map's
// variance under the footprint (Toksvig, from the mips, material_surface); the clear coat's lobe likewise.
// Screen derivatives of the mapped normal
// were tried instead of (2): they widen the lobe far too much at the map's discontinuities. Measured against the
// converged reference (docs/assets.md). Fragment stages only (screen derivatives).
#ifndef COMPUTE_STAGE
void material_antialias(vec3 n) {
    vec3 du = dFdx(n), dv = dFdy(n);
    float widening = min(2.0 * 0.15 * (dot(du, du) + dot(dv, dv)), 0.2);
    g_alpha = sqrt(clamp(g_alpha * g_alpha + widening + g_normal_variance, 1e-6, 1.0));
#if BRDF_GLTF_COAT
    g_coat_alpha = sqrt(clamp(g_coat_alpha * g_coat_alpha + widening + g_coat_normal_variance, 1e-6, 1.0));
#endif
}
#endif

// One midpoint sample of an area light stands for a patch of angular radius rho: on a near-mirror the sharp lobe
// would show each sample as a dot. The lobe is widened by the patch, alpha^2 + 0.05 rho^2, so that the samples'
// lobes meet (GGX stays normalised). The constant is measured (docs/assets.md): a roughness-0.02 metal sphere
// under a quad light, 8 x 8 samples, against the reference: 15.9 % unwidened, 6.0 % at 0.05, 11.9 % at 0.1, 40 %
// at 0.25 (too blurred); the helmet of the gallery: 17 %, 1.6 %, 1.0 %, 1.2 %.
#define MATERIAL_PATCH_EVAL 1
vec3 brdf_eval(vec3 wo, vec3 wi);
vec3 brdf_eval_patch(vec3 wo, vec3 wi, float rho) {
    float alpha = g_alpha, coat_alpha = g_coat_alpha, spread = 0.05 * rho * rho;
    g_alpha = sqrt(alpha * alpha + spread);
    g_coat_alpha = sqrt(coat_alpha * coat_alpha + spread);
    vec3 f = brdf_eval(wo, wi);
    g_alpha = alpha;
    g_coat_alpha = coat_alpha;
    return f;
}

vec3 material_emission() {
#if BRDF_GLTF_UNLIT
    return g_base;  // KHR_materials_unlit: the base colour leaves the surface as it is
#else
    return g_emission;
#endif
}
float material_occlusion() { return g_occlusion; }
// false where alpha_mode = "mask" cuts the surface away
bool material_covered() {
#if BRDF_GLTF_MASK
    return g_coverage >= m_alpha_cutoff;
#else
    return true;
#endif
}

// the weight this fragment is blended with over what lies behind it (alphaMode BLEND: its coverage), else 1
float material_alpha() {
#if BRDF_GLTF_BLEND
    return clamp(g_coverage, 0.0, 1.0);
#else
    return 1.0;
#endif
}

// the base lobe's alpha as an isotropic lobe of the same area (the split sum's and the transmission's lookups)
float gltf_lobe_alpha() {
#if BRDF_GLTF_ANISOTROPY
    return sqrt(g_alpha * mix(g_alpha, 1.0, g_anisotropy.z));
#else
    return g_alpha;
#endif
}

// The environment's split sum for this BRDF: its specular directional albedo F0 A + B (Schlick: the dielectric's
// w (F0 A + B), the metal's c A + B, mixed by metallic) and the dielectric's diffuse albedo
// (1 - m) c (1 - w (F0 + (1 - F0) P)) (F0 its largest channel), P = the mean of (1 - v.h)^5 over the cosine-weighted
// hemisphere, both from the table at mu = n.v and the roughness.
// A sheen scales both by 1 - max(C) E(mu) (the extension's simplified form for the environment) and adds its own
// albedo C E(mu) to the diffuse one: its broad lobe lit by the irradiance (an approximation: the lobe leans to
// grazing angles where the irradiance map's cosine does not; docs/assets.md measures it).
void material_ibl(float mu, out vec3 diffuse_albedo, out vec3 specular_albedo, out float alpha) {
#if BRDF_GLTF_UNLIT
    diffuse_albedo = specular_albedo = vec3(0.0);
    alpha = 1.0;
    return;
#endif
    float lobe_alpha = gltf_lobe_alpha();
    vec3 abp = ibl_table(vec2(clamp(mu, 0.0, 1.0), sqrt(lobe_alpha))).rgb;
    specular_albedo = mix(g_specular * (g_f0 * abp.x + abp.y), g_base * abp.x + abp.y, g_metallic);
    float f0_max = max(g_f0.r, max(g_f0.g, g_f0.b));  // max(F) = max(F0) + (1 - max(F0)) s: F grows with F0
    diffuse_albedo = (1.0 - g_metallic) * (1.0 - g_transmission) * g_base
                     * (1.0 - g_specular * (f0_max + (1.0 - f0_max) * abp.z));
    alpha = lobe_alpha;
#if BRDF_GLTF_SHEEN
    float sheen_albedo = gltf_sheen_albedo(mu);
    float scaling = max(1.0 - max(g_sheen.r, max(g_sheen.g, g_sheen.b)) * sheen_albedo, 0.0);
    specular_albedo *= scaling;
    diffuse_albedo = diffuse_albedo * scaling + g_sheen * sheen_albedo;
#endif
}

#if BRDF_GLTF_TRANSMISSION
// What the surface lets through of the light behind it (KHR_materials_transmission), in the split sum's terms: the
// transmission lobe is the reflection's GGX lobe mirrored through the surface, so its albedo is that lobe's with
// F = 1 (A + B of the table) less what the Fresnel reflects, w (F0 A + B), tinted by the base colour, weighted by
// (1 - m) t and by the layers above (1 - c F_c, 1 - max(C) E). Returns the weight and the lobe's alpha.
vec3 material_transmission(mat3 frame, vec3 v, out float alpha) {
    float mu = clamp(dot(frame[2], v), 0.0, 1.0);
    alpha = gltf_lobe_alpha();
    vec3 abp = ibl_table(vec2(mu, sqrt(alpha))).rgb;
    float f0 = max(g_f0.r, max(g_f0.g, g_f0.b));
    vec3 weight = (1.0 - g_metallic) * g_transmission * g_base * max(abp.x + abp.y - g_specular * (f0 * abp.x + abp.y), 0.0);
#if BRDF_GLTF_SHEEN
    weight *= max(1.0 - max(g_sheen.r, max(g_sheen.g, g_sheen.b)) * gltf_sheen_albedo(mu), 0.0);
#endif
#if BRDF_GLTF_COAT
    float coat_mu = clamp(dot(frame * g_coat_n, v), 0.0, 1.0);
    weight *= 1.0 - g_coat * (0.04 + 0.96 * pow(1.0 - coat_mu, 5.0));
#endif
    return weight;
}
#endif

#if BRDF_GLTF_COAT
// The coat's share of the environment's light: weight c F_c(v), its world normal, alpha_c and the lobe's albedo
// (A + B of the split-sum table: F0 = 1, the Fresnel being the layering's own weight).
void material_coat_ibl(mat3 frame, vec3 v, out float weight, out vec3 normal, out float alpha, out float albedo) {
    normal = frame * g_coat_n;
    float mu = clamp(dot(normal, v), 0.0, 1.0);
    weight = g_coat * (0.04 + 0.96 * pow(1.0 - mu, 5.0));
    alpha = g_coat_alpha;
    vec3 abp = ibl_table(vec2(mu, sqrt(alpha))).rgb;
    albedo = abp.x + abp.y;
}

// D_c V_c (n_c.l) / (n.l): the coat's GGX lobe about its own normal, lit with its own cosine
float gltf_coat_lobe(vec3 wo, vec3 wi) {
    float nv = dot(g_coat_n, wo), nl = dot(g_coat_n, wi);
    if (nv <= 0.0 || nl <= 0.0) return 0.0;
    float nh = dot(g_coat_n, normalize(wo + wi));
    if (nh <= 0.0) return 0.0;
    float a2 = g_coat_alpha * g_coat_alpha;
    float q = nh * nh * (a2 - 1.0) + 1.0;
    float d = a2 / (PI * q * q);
    float lv = (sqrt(1.0 + a2 * (1.0 - nv * nv) / (nv * nv)) - 1.0) * 0.5;
    float ll = (sqrt(1.0 + a2 * (1.0 - nl * nl) / (nl * nl)) - 1.0) * 0.5;
    return d / (1.0 + lv + ll) / (4.0 * nv * nl) * nl / wi.z;
}
#endif

// GGX D(h) and the Smith Lambda(w), alpha a.x along the lobe's x axis, a.y along its y
float gltf_d(vec3 h, vec2 a) {
    if (h.z <= 0.0) return 0.0;
    vec2 s = h.xy / a;
    float q = dot(s, s) + h.z * h.z;
    return 1.0 / (PI * a.x * a.y * q * q);
}
float gltf_lambda(vec3 w, vec2 a) {
    vec2 s = a * w.xy;
    float a2t2 = dot(s, s) / max(w.z * w.z, 1e-30);
    return a2t2 / (2.0 * (1.0 + sqrt(1.0 + a2t2)));
}

vec3 brdf_eval(vec3 wo, vec3 wi) {
#if BRDF_GLTF_UNLIT
    return vec3(0.0);
#endif
    if (wo.z <= 0.0 || wi.z <= 0.0) return vec3(0.0);
    vec3 h = normalize(wo + wi);
    float schlick = pow(1.0 - clamp(dot(wo, h), 0.0, 1.0), 5.0);
    vec2 a = vec2(g_alpha);
    vec3 hl = h, wol = wo, wil = wi;  // in the lobe's frame
#if BRDF_GLTF_ANISOTROPY
    a.x = mix(g_alpha, 1.0, g_anisotropy.z);  // alpha_t along the direction, alpha_b = alpha across
    mat2 into = mat2(g_anisotropy.x, -g_anisotropy.y, g_anisotropy.y, g_anisotropy.x);
    hl.xy = into * h.xy;
    wol.xy = into * wo.xy;
    wil.xy = into * wi.xy;
#endif
    float dv = gltf_d(hl, a) / ((1.0 + gltf_lambda(wol, a) + gltf_lambda(wil, a)) * 4.0 * wo.z * wi.z);
    vec3 f_d = g_f0 + (1.0 - g_f0) * schlick;  // Khronos' fresnel_mix: tinted, weighted by g_specular
    float diffuse_weight = (1.0 - g_specular * max(f_d.r, max(f_d.g, f_d.b))) * (1.0 - g_transmission);
    vec3 f_m = g_base + (1.0 - g_base) * schlick;
    vec3 value = (1.0 - g_metallic) * (diffuse_weight * g_base * INV_PI + g_specular * f_d * dv) + g_metallic * f_m * dv;
#if BRDF_GLTF_SHEEN
    value = gltf_sheened(value, wo, wi, h);
#endif
#if BRDF_GLTF_COAT
    float weight = g_coat * (0.04 + 0.96 * pow(1.0 - clamp(abs(dot(g_coat_n, wo)), 0.0, 1.0), 5.0));
    value = (1.0 - weight) * value + weight * gltf_coat_lobe(wo, wi);
#endif
    return value;
}
