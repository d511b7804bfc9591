// Provides brdf_eval(wo, wi) for the Lafortune material (twin of reflets/brdf/lafortune.py).
#define LAFORTUNE_MAX_LOBES 8
uniform vec3 m_kd;
uniform int m_lobe_count;
uniform vec3 m_lobe_c[LAFORTUNE_MAX_LOBES];
uniform float m_lobe_exponent[LAFORTUNE_MAX_LOBES];
uniform vec3 m_lobe_scale[LAFORTUNE_MAX_LOBES];

// max(0, v.w)^e; 0 where v.w <= 0, also for e = 0 (GLSL's pow(0, 0) is undefined). Near the lobe axis
// log(v.w) = log|v| + log(1 - t), t = |v/|v| - w|^2/2, from a series: no cancellation in 1 - cos, so
// large exponents keep float32 accuracy.
float lafortune_lobe(vec3 v, vec3 w, float e) {
    float x = dot(v, w);
    if (x <= 0.0) return 0.0;
    if (e <= 0.0) return 1.0;
    float len = length(v);  // > 0 since v.w > 0
    vec3 d = v / len - w;
    float t = 0.5 * dot(d, d);
    float log_x = t < 0.05
        ? log(len) - t * (1.0 + t * (1.0 / 2.0 + t * (1.0 / 3.0 + t * (1.0 / 4.0 + t * (1.0 / 5.0)))))
        : log(x);
    return exp(e * log_x);
}

vec3 brdf_eval(vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return vec3(0.0);
    vec3 f = m_kd * INV_PI;
    for (int i = 0; i < LAFORTUNE_MAX_LOBES; ++i) {
        if (i >= m_lobe_count) break;
        // C_x wo_x wi_x + C_y wo_y wi_y + C_z wo_z wi_z = (C * wo) . wi
        f += m_lobe_scale[i] * lafortune_lobe(m_lobe_c[i] * wo, wi, m_lobe_exponent[i]);
    }
    return f;
}
