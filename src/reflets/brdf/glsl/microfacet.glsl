// Provides brdf_eval(wo, wi) for the microfacet (Cook-Torrance) material, twin of reflets/brdf/microfacet.py,
// and the distribution helpers mf_d, mf_lambda (GGX / Beckmann, anisotropic) for other techniques.
// Local frame: x = tangent (alpha.x), y = bitangent (alpha.y), z = normal.
#include "reflets/brdf/glsl/fresnel.glsl"

uniform vec2 m_alpha;        // (alpha_x, alpha_y) = Mitsuba's (alpha_u, alpha_v)
// The model's switches are compile-time (material flags BRDF_MF_*): a software rasteriser runs every side
// of a branch, so uniform switches cost as much as all the code they skip (measured: 2.5× frame time).
const int m_distribution = BRDF_MF_DISTRIBUTION;  // MF_GGX or MF_BECKMANN
const int m_fresnel = BRDF_MF_FRESNEL;            // 0 none, 1 Schlick (F0 = m_specular), 2 dielectric, 3 conductor
uniform vec3 m_specular;
uniform vec3 m_eta;
uniform vec3 m_k;
const bool m_correlated = BRDF_MF_CORRELATED != 0;  // height-correlated masking-shadowing, else G1(wo) G1(wi)
uniform vec3 m_diffuse;

const int MF_GGX = 0;
const int MF_BECKMANN = 1;

// D(h), normalised so that the integral of D(h) cos(theta_h) over the hemisphere is 1; 0 for h.z <= 0.
float mf_d(vec3 h, vec2 alpha, int distribution) {
    if (h.z <= 0.0) return 0.0;
    vec2 s = h.xy / alpha;
    float z2 = h.z * h.z;
    if (distribution == MF_GGX) {
        float q = dot(s, s) + z2;  // cos^4 (1 + tan^2 (cos^2 phi / ax^2 + sin^2 phi / ay^2))^2 for unit h
        return 1.0 / (PI * alpha.x * alpha.y * q * q);
    }
    return exp(-dot(s, s) / z2) / (PI * alpha.x * alpha.y * z2 * z2);
}

// Smith Lambda(w); G1 = 1 / (1 + Lambda). Depends on |cos(theta)| only.
float mf_lambda(vec3 w, vec2 alpha, int distribution) {
    vec2 s = w.xy * alpha;
    float a2t2 = dot(s, s) / max(w.z * w.z, 1e-30);  // alpha(phi)^2 tan^2(theta)
    if (a2t2 <= 0.0) return 0.0;
    if (distribution == MF_GGX) return a2t2 / (2.0 * (1.0 + sqrt(1.0 + a2t2)));  // (-1 + sqrt(1 + a2t2)) / 2
    // Beckmann, exact: (erf(a) - 1)/2 + exp(-a^2)/(2 a sqrt(pi)) = exp(-a^2)/2 (1/(a sqrt(pi)) - erfcx(a)),
    // a = 1/(alpha tan); erfcx(a) = exp(a^2) erfc(a) from Abramowitz-Stegun 7.1.26 (|error of erfc| < 1.5e-7,
    // hence |error of Lambda| < 7.5e-8).
    float a = inversesqrt(a2t2);
    if (a > 6.0) return 0.0;  // Lambda < 1e-17
    float t = 1.0 / (1.0 + 0.3275911 * a);
    float erfcx = t * (0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
    return 0.5 * exp(-a * a) * (1.0 / (a * 1.7724538509055159) - erfcx);
}

// The lobe's colour factor specular * F(cos), F0 = specular for Schlick.
vec3 mf_fresnel(float cos_h) {
    if (m_fresnel == 1) return fresnel_schlick(cos_h, m_specular);
    if (m_fresnel == 2) return m_specular * fresnel_dielectric(cos_h, m_eta);
    if (m_fresnel == 3) return m_specular * fresnel_conductor(cos_h, m_eta, m_k);
    return m_specular;
}

vec3 brdf_eval(vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return vec3(0.0);
    vec3 h = normalize(wo + wi);
    float lo = mf_lambda(wo, m_alpha, m_distribution);
    float li = mf_lambda(wi, m_alpha, m_distribution);
    float g = m_correlated ? 1.0 / (1.0 + lo + li) : 1.0 / ((1.0 + lo) * (1.0 + li));
    float lobe = mf_d(h, m_alpha, m_distribution) * g / (4.0 * wo.z * wi.z);
    return m_diffuse * INV_PI + mf_fresnel(dot(wi, h)) * lobe;
}
