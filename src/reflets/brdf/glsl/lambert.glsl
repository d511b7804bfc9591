// Provides brdf_eval(wo, wi) for the Lambert material (twin of reflets/brdf/lambert.py).
uniform vec3 m_albedo;

vec3 brdf_eval(vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return vec3(0.0);
    return m_albedo * INV_PI;
}
