// Provides profile_rd(r): the diffusion profile R_d at distance r (mm), per RGB channel, and its cumulative
// profile_cumulative(x) = ∫₀^x R_d(u) u du — twin of
// reflets/translucency/profiles.py (constants p_* from profiles.glsl_uniforms). PROFILE: PROFILE_DIPOLE,
// PROFILE_BETTER_DIPOLE, PROFILE_NORMALIZED_DIFFUSION or PROFILE_MULTIPLE_FIT (codes from profiles.PROFILES);
// profile_incidence(mu): the light entering at outside cosine mu relative to normal incidence, 1 but for
// PROFILE_MULTIPLE_FIT (multiple_fit.incidence_factor).
#if PROFILE == PROFILE_MULTIPLE_FIT
uniform vec3 p_A;
uniform vec3 p_w;
uniform vec3 p_s1;
uniform vec3 p_s2;
uniform vec3 p_z1;
uniform vec3 p_z2;
const int INCIDENCE_NODES = 6;
uniform float p_incidence_cos[INCIDENCE_NODES];  // descending from 1
uniform vec3 p_incidence[INCIDENCE_NODES];

// R(r) = A Σ w_k s_k e^{−s_k (d_k − z_k)} / (2π d_k), d_k = sqrt(r² + z_k²) (multiple_fit.py)
vec3 profile_rd(float r) {
    vec3 d1 = sqrt(r * r + p_z1 * p_z1);
    vec3 d2 = sqrt(r * r + p_z2 * p_z2);
    vec3 first = p_w * p_s1 * exp(-p_s1 * (d1 - p_z1)) / d1;
    vec3 second = (1.0 - p_w) * p_s2 * exp(-p_s2 * (d2 - p_z2)) / d2;
    return p_A * (first + second) / (2.0 * PI);
}

// C(x) = ∫₀^x R_d(u) u du = (A/2π) Σ w_k (1 − e^{−s_k (d_k(x) − z_k)})
vec3 profile_cumulative(float x) {
    vec3 d1 = sqrt(x * x + p_z1 * p_z1);
    vec3 d2 = sqrt(x * x + p_z2 * p_z2);
    vec3 first = p_w * (1.0 - exp(-p_s1 * (d1 - p_z1)));
    vec3 second = (1.0 - p_w) * (1.0 - exp(-p_s2 * (d2 - p_z2)));
    return p_A * (first + second) / (2.0 * PI);
}

// piecewise linear in mu between the table's cosines, constant beyond them
vec3 profile_incidence(float mu) {
    if (mu >= p_incidence_cos[0]) return p_incidence[0];
    for (int i = 1; i < INCIDENCE_NODES; ++i) {
        if (mu >= p_incidence_cos[i]) {
            float t = (mu - p_incidence_cos[i]) / (p_incidence_cos[i - 1] - p_incidence_cos[i]);
            return mix(p_incidence[i], p_incidence[i - 1], t);
        }
    }
    return p_incidence[INCIDENCE_NODES - 1];
}
#elif PROFILE == PROFILE_NORMALIZED_DIFFUSION
uniform vec3 p_A;
uniform vec3 p_s;
vec3 profile_rd(float r) {
    r = max(r, 1e-6);
    return p_A * p_s * (exp(-p_s * r) + exp(-p_s * r / 3.0)) / (8.0 * PI * r);
}

// C(x) = ∫₀^x R_d(u) u du
vec3 profile_cumulative(float x) {
    return p_A / (8.0 * PI) * ((1.0 - exp(-p_s * x)) + 3.0 * (1.0 - exp(-p_s * x / 3.0)));
}
#else
uniform vec3 p_zr;
uniform vec3 p_zv;
uniform vec3 p_str;
uniform vec3 p_ce;
uniform vec3 p_cphi_over_d;
uniform vec3 p_cn;
vec3 profile_rd(float r) {
    vec3 dr = sqrt(r * r + p_zr * p_zr);
    vec3 dv = sqrt(r * r + p_zv * p_zv);
    vec3 real_source = (p_ce * p_zr * (p_str * dr + 1.0) / (dr * dr) + p_cphi_over_d) * exp(-p_str * dr) / dr;
    vec3 virtual_source = (p_ce * p_zv * (p_str * dv + 1.0) / (dv * dv) + p_cphi_over_d) * exp(-p_str * dv) / dv;
    return p_cn * (real_source - virtual_source);
}

// C(x) = ∫₀^x R_d(u) u du in closed form: with d² = u² + z², u du = d dd, and
// ∫ z (σd + 1) e^{−σd}/d² dd = −z e^{−σd}/d,  ∫ e^{−σd} dd = −e^{−σd}/σ.
vec3 dipole_source_cumulative(vec3 z, float x) {
    vec3 d = sqrt(x * x + z * z);
    vec3 az = abs(z);
    vec3 flux = p_ce * z * (exp(-p_str * az) / az - exp(-p_str * d) / d);
    vec3 fluence = p_cphi_over_d * (exp(-p_str * az) - exp(-p_str * d)) / max(p_str, vec3(1e-12));
    return flux + fluence;
}

vec3 profile_cumulative(float x) {
    return p_cn * (dipole_source_cumulative(p_zr, x) - dipole_source_cumulative(p_zv, x));
}
#endif

#if PROFILE != PROFILE_MULTIPLE_FIT
vec3 profile_incidence(float mu) { return vec3(1.0); }
#endif
