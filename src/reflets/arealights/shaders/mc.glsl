// Provides area_light_contribution() for the "mc" method (area-light document §2.6–2.7 and MIS): Monte Carlo
// integration of f L cosθx cosθy / r² over each polygon light with a_samples samples per frame.
//   METHOD_VARIANT 0 "uniform":    N samples uniform in area;  L_o ≈ L A/N Σ f cosθx cosθy / r².
//   METHOD_VARIANT 1 "two_region": the document's pdf (2.35): N/2 samples uniform in a box B around the lobe,
//                                  N/2 uniform in the rest C = A − B (rejection from the whole light);
//                                  L_o ≈ L [(2B/N) Σ_box f G + (2C/N) Σ_rest f G]   (corrected weights).
//   METHOD_VARIANT 2 "mis":        per sample one light sample and one lobe sample, power / balance heuristic.
// Random numbers: PCG hash per (pixel, u_frame, u_seed, light). Everything happens in the light's affine
// coordinates (u, v): y = c1 + u e1 + v e2 (the unit square for a parallelogram); uniform in (u, v) is
// uniform in area because the map is affine.
uniform uint u_frame;
uniform uint u_seed;
uniform int a_samples;        // N, light samples per pixel and frame (per strategy for mis)
uniform int a_heuristic;      // mis: 0 balance, 1 power (β = 2)
uniform float a_cone_sin;     // two_region: sin α, α the half-angle (wi space) of the cone holding t of the lobe
uniform float a_spec_weight;  // mis: probability of drawing the lobe rather than the cosine-weighted hemisphere

const int MC_MAX_UV = MAX_POLY_VERTICES + 4;  // a convex polygon clipped by a box gains at most 4 vertices
const int MC_MAX_TRIES = 64;                  // rejection tries; acceptance ≥ 1/2, so failure ≤ 2^-64

uint mc_rng;

float mc_cross2(vec2 a, vec2 b) { return a.x * b.y - a.y * b.x; }

// (u, v) of a point p of the light plane: least squares on (e1, e2) (exact for points of the plane).
vec2 mc_to_uv(AreaLight L, vec3 p) {
    vec3 d = p - L.c1;
    float g11 = dot(L.e1, L.e1), g12 = dot(L.e1, L.e2), g22 = dot(L.e2, L.e2);
    float b1 = dot(L.e1, d), b2 = dot(L.e2, d);
    float det = g11 * g22 - g12 * g12;
    return vec2(g22 * b1 - g12 * b2, g11 * b2 - g12 * b1) / det;
}

// The light polygon in (u, v), and the same polygon clipped to the lobe box.
vec2 mc_poly[MC_MAX_UV];
int mc_poly_n;
float mc_poly_area;  // in (u, v) units
vec2 mc_box_poly[MC_MAX_UV];
int mc_box_n;
float mc_box_area;

float mc_area_uv(vec2 p[MC_MAX_UV], int n) {
    float a = 0.0;
    for (int k = 1; k + 1 < n; ++k) a += mc_cross2(p[k] - p[0], p[k + 1] - p[0]);
    return 0.5 * abs(a);
}

void mc_light_polygon(int i, AreaLight L) {
    mc_poly_n = L.n;
    for (int k = 0; k < L.n; ++k) mc_poly[k] = mc_to_uv(L, area_vertex(i, k));
    if (L.parallelogram) {  // exactly the unit square
        mc_poly[0] = vec2(0.0); mc_poly[1] = vec2(1.0, 0.0); mc_poly[2] = vec2(1.0); mc_poly[3] = vec2(0.0, 1.0);
    }
    mc_poly_area = mc_area_uv(mc_poly, mc_poly_n);
}

// Uniform point of a convex (u, v) polygon: fan triangle chosen ∝ area, then uniform in the triangle.
vec2 mc_sample_convex(vec2 p[MC_MAX_UV], int n, float area) {
    float target = rng_next(mc_rng) * 2.0 * area;
    int k = 1;
    float a = 0.0;
    for (; k + 2 < n; ++k) {
        a = abs(mc_cross2(p[k] - p[0], p[k + 1] - p[0]));
        if (target < a) break;
        target -= a;
    }
    float s = sqrt(rng_next(mc_rng));
    float t = rng_next(mc_rng);
    return (1.0 - s) * p[0] + s * (1.0 - t) * p[k] + s * t * p[k + 1];
}

// Uniform point on the whole light (uv): the unit square for a parallelogram, else the fan.
vec2 mc_sample_light_uv(AreaLight L) {
    if (L.parallelogram) return vec2(rng_next(mc_rng), rng_next(mc_rng));
    return mc_sample_convex(mc_poly, mc_poly_n, mc_poly_area);
}

// Is the light-plane point of coordinates uv on the light? (convex polygon, counter-clockwise in uv)
bool mc_inside(AreaLight L, vec2 uv) {
    if (L.parallelogram) return all(greaterThanEqual(uv, vec2(0.0))) && all(lessThanEqual(uv, vec2(1.0)));
    for (int k = 0; k < mc_poly_n; ++k) {
        vec2 a = mc_poly[k], b = mc_poly[(k + 1) % mc_poly_n];
        if (mc_cross2(b - a, uv - a) < 0.0) return false;
    }
    return true;
}

// Connect x to a light point y: local wi, squared distance and cosθy; false when the pair carries nothing
// (y below x's horizon, or x behind a one-sided light).
bool mc_connect(AreaLight L, vec3 x, vec3 y, mat3 to_local, out vec3 wi, out float dist2, out float cos_y) {
    vec3 d = y - x;
    dist2 = dot(d, d);
    vec3 l = d * inversesqrt(max(dist2, 1e-30));
    cos_y = -dot(l, L.normal);
    if (L.two_sided) cos_y = abs(cos_y);
    wi = to_local * l;
    return dist2 > 0.0 && cos_y > 0.0 && wi.z > 0.0;
}

// Clip the light polygon (uv) to the box [lo, hi] (Sutherland-Hodgman, one axis-aligned edge at a time).
void mc_clip_to_box(vec2 lo, vec2 hi) {
    vec2 cur[MC_MAX_UV];
    int n = mc_poly_n;
    for (int k = 0; k < n; ++k) cur[k] = mc_poly[k];
    for (int e = 0; e < 4; ++e) {
        int axis = e & 1;
        float sgn = e < 2 ? 1.0 : -1.0;            // keep sgn * (p[axis] - bound) >= 0
        float bound = e < 2 ? lo[axis] : hi[axis];
        vec2 outp[MC_MAX_UV];
        int m = 0;
        for (int k = 0; k < n; ++k) {
            vec2 a = cur[k], b = cur[(k + 1) % n];
            float da = sgn * (a[axis] - bound), db = sgn * (b[axis] - bound);
            if (da >= 0.0 && m < MC_MAX_UV) outp[m++] = a;
            if ((da >= 0.0) != (db >= 0.0) && m < MC_MAX_UV) outp[m++] = mix(a, b, da / (da - db));
        }
        n = m;
        for (int k = 0; k < n; ++k) cur[k] = outp[k];
    }
    mc_box_n = n;
    for (int k = 0; k < n; ++k) mc_box_poly[k] = cur[k];
    mc_box_area = n >= 3 ? mc_area_uv(mc_box_poly, n) : 0.0;
}

// ---------------------------------------------------------------------------------------------- strategies

vec3 mc_uniform(AreaLight L, vec3 x, mat3 frame, vec3 wo, int n_samples) {
    mat3 to_local = transpose(frame);
    vec3 sum = vec3(0.0);
    for (int j = 0; j < n_samples; ++j) {
        vec2 uv = mc_sample_light_uv(L);
        vec3 wi;
        float dist2, cos_y;
        if (mc_connect(L, x, L.c1 + uv.x * L.e1 + uv.y * L.e2, to_local, wi, dist2, cos_y))
            sum += brdf_eval(wo, wi) * (wi.z * cos_y / dist2);
        g_samples += 1;
    }
    return sum * (L.area / float(n_samples));
}

// The lobe box in (u, v): bounding box, along the light's edges, of the ellipse where the cone of half-angle α
// around r meets the light plane. With the origin moved to the hit point c = x + t r and (u, v) scaled by t,
// the cone (D·r)² ≥ cos²α |D|² restricted to D = û e1 + v̂ e2 + r is the conic C of (û, v̂, 1); its tangents
// û = k solve A11 − 2k A13 + k² A33 = 0 with A = adj(C) (the dual conic), likewise for v̂.
// Returns false when there is no ellipse: the cone reaches the plane's horizon (box unbounded) or misses it.
bool mc_lobe_box(AreaLight L, vec3 x, vec3 r, out vec2 lo, out vec2 hi) {
    vec3 n_eff = dot(x - L.c1, L.normal) > 0.0 ? L.normal : -L.normal;  // light normal on x's side
    float cos_b = -dot(r, n_eff);                                         // β: angle between r and −n_eff
    if (cos_b <= a_cone_sin + 1e-4) return false;                         // ellipse iff β + α < 90°
    float t = dot(L.c1 - x, n_eff) / dot(r, n_eff);
    vec2 uvc = mc_to_uv(L, x + t * r);
    float s2 = a_cone_sin * a_cone_sin, c2 = 1.0 - s2;
    float p1 = dot(L.e1, r), p2 = dot(L.e2, r);
    float C11 = p1 * p1 - c2 * dot(L.e1, L.e1);
    float C12 = p1 * p2 - c2 * dot(L.e1, L.e2);
    float C22 = p2 * p2 - c2 * dot(L.e2, L.e2);
    float C13 = p1 * s2, C23 = p2 * s2, C33 = s2;
    float A11 = C22 * C33 - C23 * C23;
    float A22 = C11 * C33 - C13 * C13;
    float A33 = C11 * C22 - C12 * C12;
    float A13 = C12 * C23 - C13 * C22;
    float A23 = C12 * C13 - C11 * C23;
    if (A33 <= 0.0) return false;
    float du = sqrt(max(A13 * A13 - A11 * A33, 0.0)), dv = sqrt(max(A23 * A23 - A22 * A33, 0.0));
    lo = uvc + t * vec2(A13 - du, A23 - dv) / A33;
    hi = uvc + t * vec2(A13 + du, A23 + dv) / A33;
    return true;
}

vec3 mc_two_region(AreaLight L, vec3 x, mat3 frame, vec3 wo) {
    int n = a_samples;
    if (u_lobe_kind == 0) return mc_uniform(L, x, frame, wo, n);  // no lobe to steer by
    vec2 lo, hi;
    if (!mc_lobe_box(L, x, frame * mirror_direction(wo), lo, hi)) return mc_uniform(L, x, frame, wo, n);
    mc_clip_to_box(lo, hi);
    float jac = L.area / mc_poly_area;  // world area per (u, v) area
    float B = mc_box_area * jac;
    float C = L.area - B;
    // Empty box (the lobe misses the light) or box over half the light: uniform sampling (document §2.6).
    if (B <= 0.0 || B > 0.5 * L.area) return mc_uniform(L, x, frame, wo, n);
    mat3 to_local = transpose(frame);
    int n_box = n / 2, n_rest = n - n_box;  // N/2 each (n ≥ 2 is enforced in Python)
    vec3 sum_box = vec3(0.0), sum_rest = vec3(0.0);
    vec3 wi;
    float dist2, cos_y;
    for (int j = 0; j < n_box; ++j) {
        vec2 uv = L.parallelogram
            ? mix(max(lo, vec2(0.0)), min(hi, vec2(1.0)), vec2(rng_next(mc_rng), rng_next(mc_rng)))
            : mc_sample_convex(mc_box_poly, mc_box_n, mc_box_area);
        if (mc_connect(L, x, L.c1 + uv.x * L.e1 + uv.y * L.e2, to_local, wi, dist2, cos_y))
            sum_box += brdf_eval(wo, wi) * (wi.z * cos_y / dist2);
        g_samples += 1;
    }
    for (int j = 0; j < n_rest; ++j) {
        // Rejection sampling (Algorithm 1, with the test the right way round): proposal q = 1/A on the whole
        // light, target p = 1/C outside the box and 0 inside, bound M = sup p/q = A/C; accept when
        // u2 < p(y) / (M q(y)). That ratio is exactly 1 outside the box and 0 inside (written as such, not
        // computed in float), so with u2 in [0, 1) this accepts exactly the points outside the box; the
        // acceptance probability is C/A ≥ 1/2 (B ≤ A/2 here), so MC_MAX_TRIES failures have p ≤ 2^-64.
        for (int tries = 0; tries < MC_MAX_TRIES; ++tries) {
            vec2 uv = mc_sample_light_uv(L);
            bool in_box = all(greaterThanEqual(uv, lo)) && all(lessThanEqual(uv, hi));
            float ratio = in_box ? 0.0 : 1.0;  // p(y) / (M q(y))
            if (rng_next(mc_rng) < ratio) {
                if (mc_connect(L, x, L.c1 + uv.x * L.e1 + uv.y * L.e2, to_local, wi, dist2, cos_y))
                    sum_rest += brdf_eval(wo, wi) * (wi.z * cos_y / dist2);
                break;
            }
        }
        g_samples += 1;
    }
    return sum_box * (B / float(n_box)) + sum_rest * (C / float(n_rest));  // 2B/N and 2C/N for even N
}

// ------------------------------------------------------------------------------------ MIS: light ⊕ lobe

// max(0, cos α)^e (0 behind the axis, also for e = 0) from unit a, w; log(1 − t) by series near the axis so
// large exponents keep float32 accuracy.
float mc_pow_lobe(vec3 a, vec3 w, float e) {
    float c = dot(a, w);
    if (c <= 0.0) return 0.0;
    if (e <= 0.0) return 1.0;
    vec3 d = a - w;
    float t = 0.5 * dot(d, d);
    float log_c = t < 0.05 ? -t * (1.0 + t * (0.5 + t * (1.0 / 3.0 + t * (0.25 + t * 0.2)))) : log(c);
    return exp(e * log_c);
}

// Density (solid angle, local frame) of mc_sample_lobe: mixture of the cosine-weighted hemisphere (weight
// 1 − a_spec_weight) and the lobe: (e + 1)/(2π) cos^e around r (kind 1), or the half vector h drawn with
// (e + 1)/(2π) cos^e θh around n, p(wi) = p(h) / (4 wo·h) (kind 2).
float mc_lobe_pdf(vec3 wo, vec3 wi) {
    float e = u_lobe_exponent;
    float p_cos = max(wi.z, 0.0) * INV_PI;
    float p_spec = 0.0;
    if (u_lobe_kind == 1) {
        p_spec = (e + 1.0) / TWO_PI * mc_pow_lobe(mirror_direction(wo), wi, e);
    } else if (u_lobe_kind == 2) {
        vec3 hs = wo + wi;
        float len2 = dot(hs, hs);
        if (len2 > 1e-12) {
            vec3 h = hs * inversesqrt(len2);
            float oh = dot(wo, h);
            if (oh > 0.0) p_spec = (e + 1.0) / TWO_PI * mc_pow_lobe(vec3(0.0, 0.0, 1.0), h, e) / (4.0 * oh);
        }
    }
    return mix(p_cos, p_spec, a_spec_weight);
}

// Draw wi (local) from mc_lobe_pdf; false for a failed sample (half vector facing away from wo).
bool mc_sample_lobe(vec3 wo, out vec3 wi) {
    float u0 = rng_next(mc_rng), u1 = rng_next(mc_rng), u2 = rng_next(mc_rng);
    float phi = TWO_PI * u2;
    if (u0 >= a_spec_weight || u_lobe_kind == 0) {  // cosine-weighted (Malley)
        float s = sqrt(u1);
        wi = vec3(s * cos(phi), s * sin(phi), sqrt(max(0.0, 1.0 - u1)));
        return true;
    }
    float cos_a = pow(1.0 - u1, 1.0 / (u_lobe_exponent + 1.0));
    float sin_a = sqrt(max(0.0, 1.0 - cos_a * cos_a));
    vec3 axis = u_lobe_kind == 1 ? mirror_direction(wo) : vec3(0.0, 0.0, 1.0);
    vec3 d = shading_frame(axis, vec4(0.0)) * vec3(sin_a * cos(phi), sin_a * sin(phi), cos_a);
    if (u_lobe_kind == 1) {
        wi = d;
        return true;
    }
    float oh = dot(wo, d);  // d is the half vector
    wi = 2.0 * oh * d - wo;
    return oh > 0.0;
}

float mc_mis_weight(float p_this, float p_other) {
    if (p_this <= 0.0) return 0.0;
    float q = p_other / p_this;
    return a_heuristic == 1 ? 1.0 / (1.0 + q * q) : 1.0 / (1.0 + q);
}

vec3 mc_mis(AreaLight L, vec3 x, mat3 frame, vec3 wo) {
    mat3 to_local = transpose(frame);
    vec3 sum = vec3(0.0);
    vec3 wi;
    float dist2, cos_y;
    for (int j = 0; j < a_samples; ++j) {
        // Light sample: uniform in area, p_light(ω) = r² / (A cosθy).
        vec2 uv = mc_sample_light_uv(L);
        if (mc_connect(L, x, L.c1 + uv.x * L.e1 + uv.y * L.e2, to_local, wi, dist2, cos_y)) {
            float p_l = dist2 / (L.area * cos_y);
            float w = mc_mis_weight(p_l, mc_lobe_pdf(wo, wi));
            sum += brdf_eval(wo, wi) * (wi.z * w / p_l);
        }
        g_samples += 1;
        // Lobe sample, traced to the light's plane and tested against the polygon.
        if (mc_sample_lobe(wo, wi) && wi.z > 0.0) {
            vec3 dir = frame * wi;
            float denom = dot(dir, L.normal);
            float t = denom != 0.0 ? dot(L.c1 - x, L.normal) / denom : -1.0;
            cos_y = L.two_sided ? abs(denom) : -denom;
            if (t > 0.0 && cos_y > 0.0 && mc_inside(L, mc_to_uv(L, x + t * dir))) {
                float p_b = mc_lobe_pdf(wo, wi);
                float p_l = t * t / (L.area * cos_y);
                sum += brdf_eval(wo, wi) * (wi.z * mc_mis_weight(p_b, p_l) / p_b);
            }
        }
        g_samples += 1;
    }
    return sum / float(a_samples);
}

vec3 area_light_contribution(int i, vec3 x, mat3 frame, vec3 wo) {
    AreaLight L = area_light(i);
    if (!area_light_faces(L, x) || wo.z <= 0.0) return vec3(0.0);  // V1; nothing is seen from below
    mc_rng = rng_seed(uvec2(gl_FragCoord.xy), u_frame, u_seed ^ pcg_hash(uint(i) + 0x9e3779b9u));
    mc_light_polygon(i, L);
#if METHOD_VARIANT == 0
    vec3 s = mc_uniform(L, x, frame, wo, a_samples);
#elif METHOD_VARIANT == 1
    vec3 s = mc_two_region(L, x, frame, wo);
#else
    vec3 s = mc_mis(L, x, frame, wo);
#endif
    return L.radiance * s;
}
