// Provides brdf_eval(wo, wi) for the mirror material (its Lambertian part: the delta lobe has no finite value)
// and mirror_reflectance(cos), the weight of mirror-reflected radiance (twin of reflets/brdf/mirror.py).
#include "reflets/brdf/glsl/fresnel.glsl"
uniform vec3 m_diffuse;
uniform vec3 m_reflectance;
uniform vec3 m_eta;
uniform vec3 m_k;

vec3 brdf_eval(vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return vec3(0.0);
    return m_diffuse * INV_PI;
}

vec3 mirror_reflectance(float cos_i) {
#if BRDF_MIRROR_CONDUCTOR
    return fresnel_conductor(cos_i, m_eta, m_k);
#else
    return m_reflectance;
#endif
}
