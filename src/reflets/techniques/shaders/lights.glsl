// Provides direct_lighting(x, frame, wo): point, directional, sampled area and environment lights.
// Light data arrive in std430 buffers filled by reflets/techniques/forward.py (layouts documented there).
layout(std430, binding = 0) readonly buffer PointLights { vec4 point_data[]; };   // position, intensity
layout(std430, binding = 1) readonly buffer DirLights { vec4 dir_data[]; };       // to-light dir, irradiance
layout(std430, binding = 2) readonly buffer AreaSamples { vec4 area_data[]; };    // (y, dA), (n_L, two_sided), (L, shadow code)
layout(std430, binding = 3) readonly buffer EnvSamples { vec4 env_data[]; };      // direction, L * solid angle

#include "reflets/techniques/shaders/shadows.glsl"

// Light counts N_POINT, N_DIR, N_AREA, N_ENV are compile-time flags, and a light type the scene lacks gets no
// code at all: on llvmpipe a loop whose trip count is a constant 0 still costs nearly a light's shading
// (measured: three such loops next to one GGX point light tripled its frame time).

// Outgoing radiance from all lights at x; `frame` maps local (t, b, n) to world, wo is local.
vec3 direct_lighting(vec3 x, mat3 frame, vec3 wo) {
    mat3 to_local = transpose(frame);
    vec3 n = frame[2];
    vec3 sum = vec3(0.0);
#if N_POINT > 0
    for (int i = 0; i < N_POINT; ++i) {
        vec3 d = point_data[2 * i].xyz - x;
        float r2 = dot(d, d);
        vec3 wi = d * inversesqrt(r2);
        float cos_x = dot(n, wi);
        if (cos_x <= 0.0) continue;
        float v = point_visibility(i, x, n);
        if (v <= 0.0) continue;
        sum += brdf_eval(wo, to_local * wi) * point_data[2 * i + 1].rgb * (v * cos_x / r2);
    }
#endif
#if N_DIR > 0
    for (int i = 0; i < N_DIR; ++i) {
        vec3 wi = dir_data[2 * i].xyz;
        float cos_x = dot(n, wi);
        if (cos_x <= 0.0) continue;
        float v = dir_visibility(i, x, n);
        if (v <= 0.0) continue;
        sum += brdf_eval(wo, to_local * wi) * dir_data[2 * i + 1].rgb * (v * cos_x);
    }
#endif
    // Area lights as weighted midpoint samples (eq 2.8 of the area-light document): f L cosθx cosθy / r² dA.
    // Shadows: each light's soft-shadow ratio (shadows.glsl), computed once per run of its samples.
#if N_AREA > 0
    float shadow_code = -1.0, shadow = 1.0;
    for (int i = 0; i < N_AREA; ++i) {
        vec4 p = area_data[3 * i];
        vec4 nl = area_data[3 * i + 1];
        vec3 d = p.xyz - x;
        float r2 = dot(d, d);
        vec3 wi = d * inversesqrt(r2);
        float cos_x = dot(n, wi);
        float cos_y = -dot(nl.xyz, wi);
        if (nl.w > 0.5) cos_y = abs(cos_y);
        if (cos_x <= 0.0 || cos_y <= 0.0) continue;
        if (area_data[3 * i + 2].w != shadow_code) {
            shadow_code = area_data[3 * i + 2].w;
            shadow = soft_visibility(shadow_code, x, frame, wo);
        }
        sum += brdf_eval(wo, to_local * wi) * area_data[3 * i + 2].rgb * (shadow * cos_x * cos_y * p.w / r2);
    }
#endif
#if N_ENV > 0
    for (int i = 0; i < N_ENV; ++i) {
        vec3 wi = env_data[2 * i].xyz;
        float cos_x = dot(n, wi);
        if (cos_x <= 0.0) continue;
        sum += brdf_eval(wo, to_local * wi) * env_data[2 * i + 1].rgb * cos_x;
    }
#endif
    return sum;
}
