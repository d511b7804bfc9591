// Provides area_light_contribution() for the "adaptive" method (§2.4 of the area-light document): the grid
// step Δ (fraction of the light width) is predicted per fragment and light from the normalised distance d to
// the light's nearest point and the material's lobe (predictors.py holds the same formulas in NumPy).
#include "reflets/arealights/shaders/grid.glsl"

uniform vec3 a_safety;       // safety factors of the Lambert, Phong and Blinn-Phong predictors
uniform float a_min_step;    // floor of Δ (0.05: at most 20 × 20 samples on a square light)
uniform bool a_dither;       // eq 2.21: Δ = max(floor, Δ − 0.1 ξ), ξ uniform per fragment and light
uniform int a_seed;
uniform float a_blinn_power; // outer exponent of the Blinn-Phong fit (1/2.4589, or 2.4589 as printed)

const int ADAPTIVE_MAX_SIDE = 128;  // cap of the long side's sample count on elongated parallelograms

// Distance from x to the nearest point of the convex polygon light i: the projection onto the plane when it
// falls inside, else the nearest point of the boundary (exact; the document's clamped (u, v) projection is
// exact only for rectangles, and its printed form only for a unit light).
float nearest_light_distance(int i, AreaLight L, vec3 x) {
    float h = dot(x - L.c1, L.normal);
    vec3 q = x - h * L.normal;
    bool inside = true;
    float best = 3.0e38;
    for (int k = 0; k < L.n; ++k) {
        vec3 a = area_vertex(i, k);
        vec3 ab = area_vertex(i, (k + 1) % L.n) - a;
        if (dot(cross(ab, q - a), L.normal) < 0.0) inside = false;
        float t = clamp(dot(x - a, ab) / dot(ab, ab), 0.0, 1.0);
        best = min(best, length(x - a - t * ab));
    }
    return inside ? abs(h) : best;
}

// Predicted step for normalised distance d (eqs 2.9, 2.12 corrected, 2.13), times the safety factors: the
// specular predictor of the material's lobe, and the Lambert one where there is a diffuse part (or no lobe).
float predicted_step(float d) {
    float step = 3.0e38;
    if (u_lobe_kind == 0 || any(greaterThan(u_lobe_diffuse, vec3(0.0))))
        step = a_safety.x * (d < 1.3 ? 0.727 * d + 0.055 : 1.0);
    float e = max(u_lobe_exponent, 1e-12);
    if (u_lobe_kind == 1) {
        float s = pow(1.6464 * pow(max(d - 0.0327, 0.0), 2.1252) / e, 1.0 / 2.0990) + 0.0017;
        step = min(step, a_safety.y * s);
    } else if (u_lobe_kind == 2) {
        float s = pow(2.6419 * pow(d + 0.1364, 2.0780) / e, a_blinn_power) + 0.0082;
        step = min(step, a_safety.z * s);
    }
    return step;
}

vec3 area_light_contribution(int i, vec3 x, mat3 frame, vec3 wo) {
    AreaLight L = area_light(i);
    if (!area_light_faces(L, x)) return vec3(0.0);
    float step = predicted_step(nearest_light_distance(i, L, x) / L.width);
    if (a_dither) {
        uint state = rng_seed(uvec2(gl_FragCoord.xy), uint(i), uint(a_seed));
        step = max(a_min_step, step - 0.1 * rng_next(state));
    }
    step = clamp(step, a_min_step, 1.0);
    int n = int(ceil(1.0 / step - 1e-4));  // quantised: Δ → 1/ceil(1/Δ), an exact n × n grid
    if (!L.parallelogram) return grid_fan(i, L, x, frame, wo, n, vec3(0.0));
    // The same spacing (1/n light widths) along e2: n_v = ceil(n |e2| / |e1|), = n on a square light.
    int nv = clamp(int(ceil(float(n) * length(L.e2) / L.width - 1e-4)), 1, ADAPTIVE_MAX_SIDE);
    return grid_parallelogram(L, x, frame, wo, vec2(0.0), vec2(1.0), n, nv, vec3(0.0));
}
