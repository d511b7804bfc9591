// Provides brdf_eval(wo, wi) for the Phong material (twin of reflets/brdf/phong.py).
uniform vec3 m_kd;
uniform vec3 m_ks;
uniform float m_exponent;
uniform bool m_normalized;

// max(0, x)^e, zero for x <= 0 (also when e = 0): avoids GLSL's undefined pow(0, 0) and pow of negatives.
float phong_lobe(float x, float e) {
    if (x <= 0.0) return 0.0;
    return e > 0.0 ? exp(e * log(x)) : 1.0;
}

vec3 brdf_eval(vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return vec3(0.0);
    float cos_r = wo.z * wi.z - wo.x * wi.x - wo.y * wi.y;  // r·wi with r = reflect(wo, n)
    float lobe = phong_lobe(cos_r, m_exponent);
    float spec = m_normalized ? (m_exponent + 2.0) / TWO_PI * lobe : lobe / wi.z;
    return m_kd * INV_PI + m_ks * spec;
}
