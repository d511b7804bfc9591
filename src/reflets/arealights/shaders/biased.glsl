// Provides area_light_contribution() for the "biased" method (§2.5 of the area-light document): the diffuse
// term exactly (Lambert's polygon formula, polygon.glsl), the rest of the BRDF by a constant a_grid × a_grid
// midpoint grid over the part of the light inside the cone of useful directions around the mirror direction.
// Masked quad lights (LIGHT_MASKS): the diffuse part on a whole-light grid instead of the exact formula.
#include "reflets/arealights/shaders/grid.glsl"

uniform int a_grid;            // n: n × n samples over the box
uniform float a_cone;          // cone half-angle α (radians) of the material's lobe, solved in biased.py
uniform int a_box;             // 0: exact ellipse's bounding box, 1: the document's square (eq 2.24), 2: both

const float HALF_PI = 1.57079632679489661923;

// The (u, v) box of parallelogram light L (S(u, v) = c1 + u e1 + v e2) bounding the cone of half-angle alpha
// around the ray x + t r, clipped to [0, 1]². Returns false when the cone misses the light (nothing to add).
bool cone_box(AreaLight L, vec3 x, vec3 r, float alpha, out vec2 lo, out vec2 hi) {
    lo = vec2(0.0);
    hi = vec2(1.0);
    float side = dot(x - L.c1, L.normal);
    vec3 nf = side > 0.0 ? L.normal : -L.normal;  // the light's normal on x's side
    float h = abs(side);                          // height of x over the light's plane
    float cos_b = -dot(r, nf);                    // β: angle between r and the direction to the plane
    float beta = acos(clamp(cos_b, -1.0, 1.0));
    if (beta - alpha >= HALF_PI) return false;    // the whole cone points away from the plane
    if (beta + alpha >= HALF_PI) return true;     // parabola / hyperbola (or r misses the plane): whole light
    float d = h / cos_b;                          // distance from x to the hit point c along r
    vec3 c = x + d * r;
    // Dual basis of (e1, e2): u = (p − c1)·du, v = (p − c1)·dv for p in the plane (any parallelogram).
    float g11 = dot(L.e1, L.e1);
    float g12 = dot(L.e1, L.e2);
    float g22 = dot(L.e2, L.e2);
    float det = g11 * g22 - g12 * g12;
    vec3 du = (g22 * L.e1 - g12 * L.e2) / det;
    vec3 dv = (g11 * L.e2 - g12 * L.e1) / det;
    vec2 centre = vec2(dot(c - L.c1, du), dot(c - L.c1, dv));
    float sin_a = sin(alpha);
    vec2 box_lo = vec2(1e30), box_hi = vec2(-1e30);
    if (a_box != 0) {
        // Eq 2.24: a square of half-width d sin α / cos β around c, aligned with the light's edges.
        vec2 half_size = d * sin_a / cos_b / vec2(length(L.e1), length(L.e2));
        box_lo = centre - half_size;
        box_hi = centre + half_size;
    }
    if (a_box != 1) {
        // The exact ellipse: along t (r's direction within the plane) it spans [c − near, c + far], across
        // it its half-width is h sin α / sqrt(cos(β − α) cos(β + α)); its (u, v) bounding box is exact.
        vec3 t = r + cos_b * nf;
        float len_t = length(t);
        t = len_t > 1e-6 ? t / len_t : normalize(L.e1);
        vec3 s = cross(nf, t);
        float far = d * sin_a / cos(beta + alpha);
        float near = d * sin_a / cos(beta - alpha);
        float across = h * sin_a / sqrt(cos(beta - alpha) * cos(beta + alpha));
        vec3 major = 0.5 * (far + near) * t;
        vec3 minor = across * s;
        vec2 mid = centre + 0.5 * (far - near) * vec2(dot(t, du), dot(t, dv));
        vec2 half_size = vec2(length(vec2(dot(major, du), dot(minor, du))), length(vec2(dot(major, dv), dot(minor, dv))));
        box_lo = min(box_lo, mid - half_size);
        box_hi = max(box_hi, mid + half_size);
    }
    lo = max(box_lo, vec2(0.0));
    hi = min(box_hi, vec2(1.0));
    return all(greaterThan(hi, lo));
}

vec3 area_light_contribution(int i, vec3 x, mat3 frame, vec3 wo) {
    AreaLight L = area_light(i);
    if (wo.z <= 0.0 || !area_light_faces(L, x)) return vec3(0.0);
    vec3 diffuse = u_lobe_diffuse * INV_PI;
    vec3 result;
#if LIGHT_MASKS
    if (L.masked) {
        // Lambert's polygon formula needs constant radiance: a masked light's diffuse part (the whole BRDF
        // when there is no lobe) goes on an a_grid² grid over the whole light instead, the mask per sample.
        if (u_lobe_kind == 0)
            return grid_parallelogram(L, x, frame, wo, vec2(0.0), vec2(1.0), a_grid, a_grid, vec3(0.0));
        result = vec3(0.0);
        if (any(greaterThan(diffuse, vec3(0.0))))
            result = grid_parallelogram(L, x, frame, wo, vec2(0.0), vec2(1.0), a_grid, a_grid, diffuse, false);
    } else
#endif
    result = diffuse * L.radiance * polygon_irradiance(i, x, frame);
    if (u_lobe_kind == 0) return result;
    // The grids integrate f − ρ_d/π (the diffuse term is already exact).
    if (!L.parallelogram) return result + grid_fan(i, L, x, frame, wo, a_grid, diffuse);
    // Blinn-Phong: a_cone is for the equivalent Phong exponent e/4; the lobe widens as 1/cos θo across the
    // plane of incidence, so the cone does too.
    float alpha = u_lobe_kind == 2 ? min(a_cone / max(wo.z, 1e-3), HALF_PI) : a_cone;
    vec2 lo, hi;
    if (!cone_box(L, x, frame * mirror_direction(wo), alpha, lo, hi)) return result;
    return result + grid_parallelogram(L, x, frame, wo, lo, hi, a_grid, a_grid, diffuse);
}
