// Provides brdf_eval(wo, wi) for the translucent material's far-field BRDF (twin of reflets/translucency/material.py):
// Beckmann Cook-Torrance with the dielectric Fresnel, plus F_T(wi) F_T(wo) R_total / (pi c) (m_diffuse holds
// R_total / (pi c) per channel). tr_beckmann_d and tr_beckmann_g1 are shared with the translucency technique.
#include "reflets/brdf/glsl/fresnel.glsl"

uniform float m_eta;
uniform float m_roughness;  // Beckmann m; 0 = smooth interface (no glossy lobe)
uniform vec3 m_diffuse;

// An albedo map (BRDF_TR_ALBEDO_MAP: 1 + its uv set): the light leaving the medium × its texel at the exit point —
// the diffusion term here, single and multiple scattering in translucent.frag (tr_albedo()).
#if defined(BRDF_TR_ALBEDO_MAP)
#define MATERIAL_SURFACE 1
#define MATERIAL_IBL_SCALE 1
uniform sampler2D m_albedo_map;
uniform mat3 m_albedo_map_uv;  // mesh uv (v up) → image uv
vec3 g_albedo = vec3(1.0);

void material_surface(vec4 uvs, inout mat3 frame) {
    vec2 uv = BRDF_TR_ALBEDO_MAP == 2 ? uvs.zw : uvs.xy;
    g_albedo = texture(m_albedo_map, (m_albedo_map_uv * vec3(uv, 1.0)).xy).rgb;
}

// the split sum's albedo: the interface's share as it is, the rest (the diffusion term's) tinted
void material_ibl_scale(float mu, vec3 untinted, inout vec3 diffuse_albedo, inout vec3 albedo) {
    diffuse_albedo *= g_albedo;
    albedo = untinted + max(albedo - untinted, vec3(0.0)) * g_albedo;
}
#include "reflets/brdf/glsl/surface_hooks.glsl"
#endif

vec3 tr_albedo() {
#if defined(BRDF_TR_ALBEDO_MAP)
    return g_albedo;
#else
    return vec3(1.0);
#endif
}

float tr_beckmann_d(float cos_h, float m) {
    float c2 = max(cos_h * cos_h, 1e-24);
    return exp(-(1.0 - c2) / (c2 * m * m)) / (PI * m * m * c2 * c2);
}

// Smith G1, Walter et al. 2007's rational approximation.
float tr_beckmann_g1(float cos_theta, float m) {
    float a = cos_theta / (m * sqrt(max(1.0 - cos_theta * cos_theta, 1e-30)));
    return a < 1.6 ? (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a) : 1.0;
}

// The interface's glossy reflection f = F_R D G / (4 cos_o cos_i) (0 for a smooth interface).
float tr_specular(vec3 wo, vec3 wi) {
    if (m_roughness <= 0.0) return 0.0;
    vec3 h = normalize(wo + wi);
    float g = tr_beckmann_g1(wo.z, m_roughness) * tr_beckmann_g1(wi.z, m_roughness);
    return fresnel_dielectric(dot(wi, h), m_eta) * tr_beckmann_d(h.z, m_roughness) * g / (4.0 * wo.z * wi.z);
}

vec3 brdf_eval(vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return vec3(0.0);
    float ft = (1.0 - fresnel_dielectric(wi.z, m_eta)) * (1.0 - fresnel_dielectric(wo.z, m_eta));
    return m_diffuse * tr_albedo() * ft + vec3(tr_specular(wo, wi));
}
