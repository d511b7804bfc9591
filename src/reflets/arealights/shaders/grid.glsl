// Provides the midpoint-rule quadrature shared by the brute, adaptive and biased area-light methods (eq 2.8 of
// the area-light document): n_u × n_v grids over a (u, v) box of a parallelogram light, and the fan rule
// (every fan triangle split into n² sub-triangles sampled at their centroids) for other convex polygons.
// Each sample adds (f(wo, wi) − f_sub) L cosθx cosθy / r² dA; f_sub is a constant BRDF part integrated
// elsewhere (the biased method's exact diffuse term), vec3(0) to integrate the whole BRDF. A masked quad light
// (LIGHT_MASKS) weighs each parallelogram sample by its mask texel and skips the samples where it is 0.

// Unoccluded contribution of a light point y of area dA seen from x (one-sided: cosθy ≤ 0 → 0;
// two-sided: |cosθy|; horizon at x: cosθx ≤ 0 → 0). Counts one light sample. eval_brdf = false integrates
// the constant BRDF f_sub instead (biased: the diffuse part of a masked light, which its exact term cannot do).
vec3 grid_sample(AreaLight L, vec3 y, float dA, vec3 x, mat3 frame, vec3 wo, vec3 f_sub, bool eval_brdf) {
    g_samples += 1;
    vec3 d = y - x;
    float r2 = dot(d, d);
    vec3 wi = d * inversesqrt(r2);
    float cos_x = dot(frame[2], wi);
    float cos_y = -dot(L.normal, wi);
    if (L.two_sided) cos_y = abs(cos_y);
    if (cos_x <= 0.0 || cos_y <= 0.0) return vec3(0.0);
    vec3 f = eval_brdf ? brdf_eval(wo, transpose(frame) * wi) - f_sub : f_sub;
    return f * (cos_x * cos_y * dA / r2);
}

// Midpoint grid of nu × nv samples over the box [lo, hi] ⊆ [0, 1]² of a parallelogram light S(u, v) =
// c1 + u e1 + v e2, each sample weighted by the box's area / (nu nv). Returns the sum times the radiance.
vec3 grid_parallelogram(AreaLight L, vec3 x, mat3 frame, vec3 wo, vec2 lo, vec2 hi, int nu, int nv, vec3 f_sub,
                        bool eval_brdf) {
    vec2 size = hi - lo;
    float dA = L.area * size.x * size.y / float(nu * nv);
    vec3 sum = vec3(0.0);
    for (int a = 0; a < nu; ++a) {
        float u = lo.x + (float(a) + 0.5) / float(nu) * size.x;
        vec3 row = vec3(0.0);  // two-level sum: float32 rounding stays small up to 256 × 256 samples
        for (int b = 0; b < nv; ++b) {
            float v = lo.y + (float(b) + 0.5) / float(nv) * size.y;
            vec3 y = L.c1 + u * L.e1 + v * L.e2;
#if LIGHT_MASKS
            float m = L.masked ? light_mask(L, vec2(u, v)) : 1.0;
            if (m > 0.0) row += m * grid_sample(L, y, dA, x, frame, wo, f_sub, eval_brdf);
#else
            row += grid_sample(L, y, dA, x, frame, wo, f_sub, eval_brdf);
#endif
        }
        sum += row;
    }
    return L.radiance * sum;
}

vec3 grid_parallelogram(AreaLight L, vec3 x, mat3 frame, vec3 wo, vec2 lo, vec2 hi, int nu, int nv, vec3 f_sub) {
    return grid_parallelogram(L, x, frame, wo, lo, hi, nu, nv, f_sub, true);
}

// Fan rule for any convex polygon light i: triangles (v0, vk, vk+1), each split into n² congruent
// sub-triangles sampled at their centroids (the same rule as forward.py's area_light_samples).
vec3 grid_fan(int i, AreaLight L, vec3 x, mat3 frame, vec3 wo, int n, vec3 f_sub) {
    vec3 sum = vec3(0.0);
    vec3 p0 = area_vertex(i, 0);
    float inv_n = 1.0 / float(n);
    for (int k = 1; k < L.n - 1; ++k) {
        vec3 eb = area_vertex(i, k) - p0;
        vec3 ec = area_vertex(i, k + 1) - p0;
        float dA = 0.5 * length(cross(eb, ec)) * inv_n * inv_n;
        for (int a = 0; a < n; ++a) {
            vec3 row = vec3(0.0);
            for (int b = 0; a + b < n; ++b) {
                vec2 up = (vec2(a, b) + 1.0 / 3.0) * inv_n;  // corners (a,b), (a+1,b), (a,b+1)
                row += grid_sample(L, p0 + up.x * eb + up.y * ec, dA, x, frame, wo, f_sub, true);
                if (a + b <= n - 2) {
                    vec2 down = (vec2(a, b) + 2.0 / 3.0) * inv_n;  // corners (a+1,b), (a,b+1), (a+1,b+1)
                    row += grid_sample(L, p0 + down.x * eb + down.y * ec, dA, x, frame, wo, f_sub, true);
                }
            }
            sum += row;
        }
    }
    return L.radiance * sum;
}
