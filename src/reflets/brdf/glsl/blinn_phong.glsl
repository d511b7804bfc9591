// Provides brdf_eval(wo, wi) for the Blinn-Phong material (twin of reflets/brdf/blinn_phong.py).
uniform vec3 m_kd;
uniform vec3 m_ks;
uniform float m_exponent;
uniform bool m_normalized;
uniform float m_norm;  // exact normalisation c(e), computed in float64 by blinn_phong.py

vec3 brdf_eval(vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return vec3(0.0);
    vec3 h = normalize(wo + wi);
    float lobe = m_exponent > 0.0 ? pow(max(h.z, 0.0), m_exponent) : 1.0;  // pow(0, 0) is undefined in GLSL
    float spec = m_normalized ? m_norm * lobe : lobe / wi.z;
    return m_kd * INV_PI + m_ks * spec;
}
