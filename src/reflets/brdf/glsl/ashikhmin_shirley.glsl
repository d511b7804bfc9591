// Provides brdf_eval(wo, wi) for the Ashikhmin-Shirley material (twin of reflets/brdf/ashikhmin_shirley.py).
uniform vec3 m_rs;
uniform vec3 m_rd;
uniform float m_nu;
uniform float m_nv;
uniform float m_norm;  // sqrt((nu + 1)(nv + 1)) / (8 pi), computed in float64

// log of (n.h)^((nu hx^2 + nv hy^2)/(1 - hz^2)) for h = u/|u|, u.z > 0. With s = 1 - hz^2 it is
// 0.5 (nu ux^2 + nv uy^2)/|u|^2 * log(1 - s)/s: no 0/0 at h = n, no overflow for exponents up to 1e6.
float as_log_lobe(vec3 u) {
    float t2 = dot(u.xy, u.xy);
    float n2 = t2 + u.z * u.z;
    float s = t2 / n2;
    float ratio;  // log(1 - s)/s
    if (s < 0.05) {
        ratio = -(1.0 + s * (1.0 / 2.0 + s * (1.0 / 3.0 + s * (1.0 / 4.0 + s * (1.0 / 5.0 + s * (1.0 / 6.0))))));
    } else {
        ratio = log(max(u.z * u.z / n2, 1e-30)) / s;  // hz^2 directly: no rounding of 1 - s
    }
    return 0.5 * (m_nu * u.x * u.x + m_nv * u.y * u.y) / n2 * ratio;
}

// 1 - (1 - c/2)^5 expanded in x = c/2, without cancellation as c -> 0
float as_falloff(float c) {
    float x = 0.5 * c;
    return x * (5.0 + x * (-10.0 + x * (10.0 + x * (-5.0 + x))));
}

vec3 brdf_eval(vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return vec3(0.0);
    vec3 u = wo + wi;
    float len = length(u);
    float k_dot_h = 0.5 * len;  // wi.(wo + wi)/|wo + wi| = |wo + wi|/2 for unit wo, wi
    vec3 d = wo - wi;
    float c = dot(d, d) / (2.0 * (2.0 + len));  // 1 - k.h without cancellation
    float c2 = c * c;
    float lobe = exp(as_log_lobe(u));
    vec3 fresnel = m_rs + (1.0 - m_rs) * (c2 * c2 * c);
    vec3 spec = (m_norm * lobe / (k_dot_h * max(wo.z, wi.z))) * fresnel;
    float falloff = as_falloff(wo.z) * as_falloff(wi.z);
    vec3 diffuse = (28.0 / 23.0 * INV_PI) * m_rd * (1.0 - m_rs) * falloff;
    return spec + diffuse;
}
