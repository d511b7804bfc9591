// Provides exact dielectric and conductor Fresnel reflectance and Schlick's approximation, unpolarised light
// arriving from outside (index 1); twin of reflets/brdf/fresnel.py. cos_i is clamped to [0, 1].

// Real relative index eta = n_inside / n_outside; total internal reflection (eta < 1) gives 1.
float fresnel_dielectric(float cos_i, float eta) {
    cos_i = clamp(cos_i, 0.0, 1.0);
    // cos²θt = 1 − sin²θi/η², written so that it does not cancel at grazing incidence for η near 1: as
    // (η − 1)(η + 1) + cos²θi, which a compiler cannot reassociate into (η² + cos²θi) − 1 (NVIDIA's did, and at
    // η = 1, cos θi < 2.4e-4 the sum rounded to 1: total internal reflection at grazing, a black rim)
    float cos2_t = ((eta - 1.0) * (eta + 1.0) + cos_i * cos_i) / (eta * eta);
    if (cos2_t <= 0.0) return 1.0;  // total internal reflection
    float cos_t = sqrt(cos2_t);
    float rs = (cos_i - eta * cos_t) / max(cos_i + eta * cos_t, 1e-30);
    float rp = (eta * cos_i - cos_t) / max(eta * cos_i + cos_t, 1e-30);
    return 0.5 * (rs * rs + rp * rp);
}

vec3 fresnel_dielectric(float cos_i, vec3 eta) {
    return vec3(fresnel_dielectric(cos_i, eta.r), fresnel_dielectric(cos_i, eta.g), fresnel_dielectric(cos_i, eta.b));
}

// Complex relative index eta + i k per channel: closed form of the complex Fresnel equations (pbrt-v3 FrConductor).
vec3 fresnel_conductor(float cos_i, vec3 eta, vec3 k) {
    cos_i = clamp(cos_i, 0.0, 1.0);
    float cos2 = cos_i * cos_i;
    float sin2 = 1.0 - cos2;
    vec3 temp = eta * eta - k * k - sin2;
    vec3 a2pb2 = sqrt(temp * temp + 4.0 * eta * eta * k * k);
    vec3 a = sqrt(max(vec3(0.0), 0.5 * (a2pb2 + temp)));
    vec3 term1 = a2pb2 + cos2;
    vec3 term2 = 2.0 * a * cos_i;
    vec3 rs = (term1 - term2) / max(term1 + term2, vec3(1e-30));
    vec3 term3 = a2pb2 * cos2 + sin2 * sin2;
    vec3 term4 = term2 * sin2;
    vec3 rp = rs * (term3 - term4) / max(term3 + term4, vec3(1e-30));
    return 0.5 * (rs + rp);
}

vec3 fresnel_schlick(float cos_i, vec3 f0) {
    float m = 1.0 - clamp(cos_i, 0.0, 1.0);
    float m2 = m * m;
    return f0 + (1.0 - f0) * (m2 * m2 * m);
}
