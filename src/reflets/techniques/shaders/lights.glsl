// Provides direct_lighting(x, frame, wo): point, directional, sampled area and environment lights.
// Light data arrive in std430 buffers filled by reflets/techniques/forward.py (layouts documented there).
layout(std430, binding = 0) readonly buffer PointLights { vec4 point_data[]; };   // position, intensity
layout(std430, binding = 1) readonly buffer DirLights { vec4 dir_data[]; };       // to-light dir, irradiance
layout(std430, binding = 2) readonly buffer AreaSamples { vec4 area_data[]; };    // (y, dA), (n_L, two_sided), (L, 0)
layout(std430, binding = 3) readonly buffer EnvSamples { vec4 env_data[]; };      // direction, L * solid angle

uniform int u_n_point;
uniform int u_n_dir;
uniform int u_n_area;
uniform int u_n_env;

// Outgoing radiance from all lights at x; `frame` maps local (t, b, n) to world, wo is local.
vec3 direct_lighting(vec3 x, mat3 frame, vec3 wo) {
    mat3 to_local = transpose(frame);
    vec3 n = frame[2];
    vec3 sum = vec3(0.0);
    for (int i = 0; i < u_n_point; ++i) {
        vec3 d = point_data[2 * i].xyz - x;
        float r2 = dot(d, d);
        vec3 wi = d * inversesqrt(r2);
        float cos_x = dot(n, wi);
        if (cos_x <= 0.0) continue;
        sum += brdf_eval(wo, to_local * wi) * point_data[2 * i + 1].rgb * (cos_x / r2);
    }
    for (int i = 0; i < u_n_dir; ++i) {
        vec3 wi = dir_data[2 * i].xyz;
        float cos_x = dot(n, wi);
        if (cos_x <= 0.0) continue;
        sum += brdf_eval(wo, to_local * wi) * dir_data[2 * i + 1].rgb * cos_x;
    }
    // Area lights as weighted midpoint samples (eq 2.8 of the area-light document): f L cosθx cosθy / r² dA.
    for (int i = 0; i < u_n_area; ++i) {
        vec4 p = area_data[3 * i];
        vec4 nl = area_data[3 * i + 1];
        vec3 d = p.xyz - x;
        float r2 = dot(d, d);
        vec3 wi = d * inversesqrt(r2);
        float cos_x = dot(n, wi);
        float cos_y = -dot(nl.xyz, wi);
        if (nl.w > 0.5) cos_y = abs(cos_y);
        if (cos_x <= 0.0 || cos_y <= 0.0) continue;
        sum += brdf_eval(wo, to_local * wi) * area_data[3 * i + 2].rgb * (cos_x * cos_y * p.w / r2);
    }
    for (int i = 0; i < u_n_env; ++i) {
        vec3 wi = env_data[2 * i].xyz;
        float cos_x = dot(n, wi);
        if (cos_x <= 0.0) continue;
        sum += brdf_eval(wo, to_local * wi) * env_data[2 * i + 1].rgb * cos_x;
    }
    return sum;
}
