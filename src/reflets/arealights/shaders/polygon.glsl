// Provides polygon area lights (std430 binding 4, layout in arealights/base.py), horizon clipping
// and the exact Lambert edge integral shared by the area-light methods; g_samples counts light samples.
// LIGHT_MASKS: quad-light mask textures (binding 5, base.py), nearest texel, fetched by light_mask().
layout(std430, binding = 4) readonly buffer PolygonLights { vec4 poly_data[]; };
#if LIGHT_MASKS
layout(std430, binding = 5) readonly buffer LightMasks { float mask_data[]; };
#endif

const int POLY_STRIDE = 16;
const int MAX_POLY_VERTICES = 8;
int g_samples = 0;  // light-sample evaluations of this fragment (the benchmark's cost measure)

struct AreaLight {
    vec3 radiance;
    bool two_sided;
    vec3 c1;         // first corner / vertex
    int n;           // vertex count
    vec3 e1;         // c2 - c1
    bool parallelogram;
    vec3 e2;         // c4 - c1 (for a parallelogram)
    float area;
    vec3 normal;     // emitting normal, normalize(e1 x e2) for quads
    float width;     // |e1|, the document's light width
#if LIGHT_MASKS
    bool masked;
    int mask_offset; // first texel in mask_data (row v = 0 first)
    ivec2 mask_size; // W, H
#endif
};

AreaLight area_light(int i) {
    int b = i * POLY_STRIDE;
    AreaLight L;
    L.radiance = poly_data[b].rgb;
    L.two_sided = poly_data[b].w > 0.5;
    L.c1 = poly_data[b + 1].xyz;
    L.n = int(poly_data[b + 1].w + 0.5);
    L.e1 = poly_data[b + 2].xyz;
    L.parallelogram = poly_data[b + 2].w > 0.5;
    L.e2 = poly_data[b + 3].xyz;
    L.area = poly_data[b + 3].w;
    L.normal = poly_data[b + 4].xyz;
    L.width = poly_data[b + 4].w;
#if LIGHT_MASKS
    vec4 m = poly_data[b + 13];
    L.masked = m.w > 0.5;
    L.mask_offset = int(m.x + 0.5);
    L.mask_size = ivec2(m.yz + 0.5);
#endif
    return L;
}

#if LIGHT_MASKS
// Mask value at (u, v) of a masked parallelogram light: the nearest texel, clamped at the edges (the same
// cells as scene/lightmask.py's mask_lookup).
float light_mask(AreaLight L, vec2 uv) {
    ivec2 t = clamp(ivec2(floor(uv * vec2(L.mask_size))), ivec2(0), L.mask_size - 1);
    return mask_data[L.mask_offset + t.y * L.mask_size.x + t.x];
}
#endif

vec3 area_vertex(int i, int k) { return poly_data[i * POLY_STRIDE + 5 + k].xyz; }

// Is x on an emitting side of the light's plane?
bool area_light_faces(AreaLight L, vec3 x) {
    float side = dot(x - L.c1, L.normal);
    return L.two_sided ? side != 0.0 : side > 0.0;
}

// Clip a polygon (vertices relative to the shading point, in the local frame, z = normal) to z >= 0.
// Sutherland-Hodgman; returns the new vertex count (0..MAX_POLY_VERTICES + 1).
int clip_to_horizon(inout vec3 v[MAX_POLY_VERTICES + 1], int n) {
    vec3 out_v[MAX_POLY_VERTICES + 1];
    int m = 0;
    for (int k = 0; k < n; ++k) {
        vec3 a = v[k];
        vec3 b = v[(k + 1) % n];
        bool ina = a.z >= 0.0;
        bool inb = b.z >= 0.0;
        if (ina) out_v[m++] = a;
        if (ina != inb) out_v[m++] = mix(a, b, a.z / (a.z - b.z));
        if (m >= MAX_POLY_VERTICES + 1) break;
    }
    for (int k = 0; k < m; ++k) v[k] = out_v[k];
    return m;
}

// Σ over edges of θ_k (Γ_k · z) for directions v (need not be normalised): the unnormalised vector form factor's
// z component (Lambert 1760). atan2(|a x b|, a.b) stays accurate for nearly parallel edges.
float edge_integral_z(vec3 v[MAX_POLY_VERTICES + 1], int n) {
    float sum = 0.0;
    for (int k = 0; k < n; ++k) {
        vec3 a = normalize(v[k]);
        vec3 b = normalize(v[(k + 1) % n]);
        vec3 c = cross(a, b);
        float s = length(c);
        if (s > 1e-12) sum += atan(s, dot(a, b)) * c.z / s;
    }
    return sum;
}

// Irradiance at x (normal frame[2]) from light i of unit radiance: E = ½ |Σ θ Γ·n| after horizon clipping.
float polygon_irradiance(int i, vec3 x, mat3 frame) {
    AreaLight L = area_light(i);
    if (!area_light_faces(L, x)) return 0.0;
    mat3 to_local = transpose(frame);
    vec3 v[MAX_POLY_VERTICES + 1];
    for (int k = 0; k < L.n; ++k) v[k] = to_local * (area_vertex(i, k) - x);
    int m = clip_to_horizon(v, L.n);
    if (m < 3) return 0.0;
    return 0.5 * abs(edge_integral_z(v, m));
}
