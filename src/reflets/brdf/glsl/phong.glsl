// Provides brdf_eval(wo, wi) for the Phong material (twin of reflets/brdf/phong.py).
uniform vec3 m_kd;
uniform vec3 m_ks;
uniform float m_exponent;
uniform bool m_normalized;

// max(0, a.w)^e for unit a, w; 0 where a.w <= 0, also for e = 0 (GLSL's pow(0, 0) is undefined). Near the
// axis log(a.w) = log(1 - t), t = |a - w|^2/2, from a series: no cancellation in 1 - a.w, so large
// exponents (e in the thousands) keep float32 accuracy.
float phong_lobe(vec3 a, vec3 w, float e) {
    float c = dot(a, w);
    if (c <= 0.0) return 0.0;
    if (e <= 0.0) return 1.0;
    vec3 d = a - w;
    float t = 0.5 * dot(d, d);
    float log_c = t < 0.05 ? -t * (1.0 + t * (1.0 / 2.0 + t * (1.0 / 3.0 + t * (1.0 / 4.0 + t * (1.0 / 5.0))))) : log(c);
    return exp(e * log_c);
}

vec3 brdf_eval(vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return vec3(0.0);
    float lobe = phong_lobe(vec3(-wo.xy, wo.z), wi, m_exponent);  // around r = reflect(wo, n)
    float spec = m_normalized ? (m_exponent + 2.0) / TWO_PI * lobe : lobe / wi.z;
    return m_kd * INV_PI + m_ks * spec;
}
