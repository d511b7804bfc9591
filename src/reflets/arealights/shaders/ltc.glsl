// Provides area_light_contribution() for the "ltc" method: Linearly Transformed Cosines (Heitz, Dupuy, Hill &
// Neubelt 2016). The material's lobe f·cos ≈ magnitude · D_M, D_M the clamped cosine seen through a 3×3 matrix
// M looked up per (view angle, roughness) in a table fitted by ltc_fit.py; the polygon integral of D_M is the
// clamped cosine's integral over the polygon M⁻¹P (Lambert's formula after clipping to z ≥ 0). The Lambertian
// term ρ_d/π is integrated with the identity matrix. Defines (from ltc.py / ltc_fit.py): LTC_SIZE_THETA,
// LTC_SIZE_ROUGH (the table's size), LTC_EDGE_P, LTC_EDGE_Q (θ/sinθ approximation), LTC_DIFFUSE and LTC_LOBE
// (1 when the material has a Lambertian term / a fitted lobe: compile-time, since a software rasteriser runs
// both sides of a branch), LTC_UNIFORM_LIGHTS (> 0: the polygon-light records, in the layout of the light
// buffer, also come as a uniform array of that many lights, read instead of the buffer: uniform loads are
// broadcasts, buffer loads are per-pixel gathers on llvmpipe), LTC_VERTICES (> 0: every polygon light of the
// scene has that many vertices, so the edge loops have a constant trip count and unroll), LTC_POWER (the
// table's base: 1 the clamped cosine; odd n > 1 the mixture (1 − β) clamped cosine + β cosⁿ, β per cell in the
// magnitude texture's alpha, whose polygon integral adds (n − 1)/2 recurrence steps per edge), LTC_CUT (with a
// mixture: the cosine of the cone outside which the cosⁿ lobe is cut off, see ltc_polygon_integral),
// LTC_FRAGMENT (1: the material gives its parameters per fragment — a textured glTF material, through
// material_ibl — and the GGX family table is read at each fragment's roughness; LTC_SQRT_ALPHA_MIN: the
// table's √α_min, for the roughness coordinate).

// LTC_PROFILE (cost breakdown only; the images are wrong): 0 everything; otherwise drop one stage to time it.
// (macros, not constants: an undefined name in #if silently reads 0)
#define LTC_PROFILE_NO_CLIP 1     // edges without horizon clipping
#define LTC_PROFILE_NO_FETCH 2    // constant matrix and magnitude instead of the two table fetches
#define LTC_PROFILE_NO_EDGES 3    // per-fragment setup (fetches, frame rotation) but no polygon integral
#define LTC_PROFILE_FRAME_ONLY 4  // nothing beyond the forward pass's shading frame

uniform sampler2D a_ltc_minv;       // (m02, m11, m20, m22) of a multiple of M⁻¹ = [[1,0,m02],[0,m11,0],[m20,0,m22]]
uniform sampler2D a_ltc_magnitude;  // ∫ f cos dω per RGB channel; alpha: the mixture weight β of cosⁿ
uniform float a_ltc_roughness;      // the material's roughness coordinate r ∈ [0, 1] (0 for one-material tables)
uniform vec3 a_ltc_scale;           // RGB factor on the table's magnitude (specular / ks of the material)
uniform vec3 a_ltc_diffuse;         // Lambertian albedo ρ_d

#if LTC_UNIFORM_LIGHTS > 0
uniform vec4 a_ltc_lights[LTC_UNIFORM_LIGHTS * POLY_STRIDE];
vec4 ltc_light_row(int i, int row) { return a_ltc_lights[i * POLY_STRIDE + row]; }
#else
vec4 ltc_light_row(int i, int row) { return poly_data[i * POLY_STRIDE + row]; }
#endif
vec3 ltc_vertex(int i, int k) { return ltc_light_row(i, 5 + k).xyz; }

// Texture coordinates of (cosθ, r): mirrors ltc_fit.lookup_coordinates (axis u = sqrt(1 − cosθ); entry i of
// n at the texel centre (i + ½)/n, so bilinear filtering interpolates between fitted cells).
vec2 ltc_lookup(float cos_theta, float roughness) {
    vec2 n = vec2(float(LTC_SIZE_THETA), float(LTC_SIZE_ROUGH));
    vec2 c = vec2(sqrt(1.0 - clamp(cos_theta, 0.0, 1.0)), clamp(roughness, 0.0, 1.0));
    return (c * (n - 1.0) + 0.5) / n;
}

// θ/sinθ for x = cosθ ∈ [−1, 1], given 1/sinθ: a rational fit on [0, 1] (relative error 6e-7,
// ltc_fit.fit_theta_over_sin), and θ(x) = π − θ(−x) below 0, where π/sinθ needs an accurate sinθ.
float ltc_theta_over_sin(float x, float inv_sin_theta) {
    float y = abs(x);
    float r = (LTC_EDGE_P.x + y * (LTC_EDGE_P.y + y * LTC_EDGE_P.z)) / (1.0 + y * (LTC_EDGE_Q.x + y * LTC_EDGE_Q.y));
    return x >= 0.0 ? r : PI * inv_sin_theta - r;
}

// Edge term θ (Γ·z) of unit vectors a → b: θ/sinθ · (a × b).z with sinθ = |a × b| (not sqrt(1 − cos²θ),
// which cancels for nearly opposite a and b — the horizon edge of a clipped polygon can span almost π).
float ltc_edge(vec3 a, vec3 b) {
    vec3 c = cross(a, b);
    return ltc_theta_over_sin(dot(a, b), inversesqrt(max(dot(c, c), 1e-30))) * c.z;
}

#if LTC_POWER > 1
// Σ_{k = 2, 4, …, n − 1} J_k of the arc a → b, J_k = ∫ h^k ds with h the arc's z coordinate (θ = J_0): the
// recurrence J_k = ((k − 1) C² J_{k−2} − [h^{k−1} h']_a^b)/k of Arvo's axial moments; mirrors
// ltc_fit.power_edge_sum. The edge's cosⁿ term is Γ_z (θ + this): for odd n, (n + 1)/(2π) ∫_P zⁿ
// = (1/2π) Σ_edges Γ_z Σ_{k even < n} J_k. Also raises z_max to the arc's highest z (C = sqrt(C²) where h
// peaks inside the arc, else the higher end).
float ltc_power_sum(vec3 a, vec3 b, float cos_theta, float inv_sin, float theta, inout float z_max) {
    float slope_a = (b.z - cos_theta * a.z) * inv_sin;  // h'(0) and h'(θ): the arc's z slope at its ends
    float slope_b = (b.z * cos_theta - a.z) * inv_sin;
    float c2 = a.z * a.z + slope_a * slope_a;
    z_max = max(z_max, slope_a > 0.0 && slope_b < 0.0 ? sqrt(c2) : max(a.z, b.z));
    float pa = a.z * slope_a, pb = b.z * slope_b;  // h^{k−1} h' at both ends
    float a2 = a.z * a.z, b2 = b.z * b.z;
    float j = theta, sum = 0.0;
    for (int k = 2; k < LTC_POWER; k += 2) {
        j = (float(k - 1) * c2 * j - (pb - pa)) / float(k);
        sum += j;
        pa *= a2;
        pb *= b2;
    }
    return sum;
}
#endif

// The edge terms of the lobe's base: sum.x += the clamped cosine's θ Γ_z (as ltc_edge); for a mixture table
// (``mixture``, a constant at every call: the branch folds away) also sum.y += Γ_z Σ J_k (cosⁿ's excess) and
// the polygon's support: support.x its highest z, support.yz the least and greatest Γ_z (all of one sign: the
// pole z is inside the polygon).
void ltc_edge_terms(vec3 a, vec3 b, bool mixture, inout vec2 sum, inout vec3 support) {
    vec3 c = cross(a, b);
    float cos_theta = dot(a, b);
    float inv_sin = inversesqrt(max(dot(c, c), 1e-30));
    float theta_over_sin = ltc_theta_over_sin(cos_theta, inv_sin);
    sum.x += theta_over_sin * c.z;
#if LTC_POWER > 1
    if (mixture) {
        sum.y += inv_sin * ltc_power_sum(a, b, cos_theta, inv_sin, theta_over_sin / inv_sin, support.x) * c.z;
        support.yz = vec2(min(support.y, c.z), max(support.z, c.z));
    }
#endif
}

// One edge a → b (unit vectors) of a polygon clipped to z ≥ 0, without building the clipped polygon: the part of
// the edge above the horizon contributes its edge terms; where the edge leaves (enters) the upper hemisphere its
// crossing point is kept as the exit (entry) point. A convex polygon crosses the horizon at most twice, and the
// clipped polygon closes with one horizon edge from the exit to the entry point (ltc_polygon_integral).
// The crossing direction is a.z b − b.z a (z = 0), turned to point between a and b: no division. An edge wholly
// below the horizon becomes the point p → p: no terms, no support.
void ltc_clipped_edge(
    vec3 a, vec3 b, bool mixture, inout vec2 sum, inout vec3 support, inout vec3 exit_point, inout vec3 entry_point
) {
#if LTC_PROFILE == LTC_PROFILE_NO_CLIP
    ltc_edge_terms(a, b, mixture, sum, support);
    return;
#endif
    bool above_a = a.z >= 0.0, above_b = b.z >= 0.0;
    vec2 q = (a.z * b.xy - b.z * a.xy) * (above_a ? 1.0 : -1.0);
    vec3 p = vec3(q * inversesqrt(max(dot(q, q), 1e-30)), 0.0);
    vec2 terms = vec2(0.0);
    ltc_edge_terms(above_a ? a : p, above_b ? b : p, mixture, terms, support);
    sum += (above_a || above_b) ? terms : vec2(0.0);
    if (above_a && !above_b) exit_point = p;
    if (!above_a && above_b) entry_point = p;
}

// LTC_HORIZON 1: the field's cheaper horizon (Hill & Heitz 2016, "Real-Time Area Lighting: a Journey from
// Research to Production"): the unclipped vector form factor F = (1/2π) Σ θ Γ, oriented towards the polygon, and
// the horizon-clipped integral of the spherical cap with the same F (|F| = sin²σ, F.z/|F| = cos of its
// elevation) in closed form (Snyder 1996). Exact where the transformed polygon lies wholly above the horizon
// (the result is F.z there); an approximation where it crosses it.
float ltc_clipped_sphere(vec3 F) {
    float l = length(F);
    return F.z * F.z > l * l * l ? max(F.z, 0.0) : max((l * l + F.z) / (l + 1.0), 0.0);
}

float ltc_polygon_integral_sphere(int i, int n, mat3 T, vec3 x) {
    vec3 first = normalize(T * (ltc_vertex(i, 0) - x));
    vec3 a = first;
    vec3 F = vec3(0.0);
    for (int k = 1; k < n; ++k) {
        vec3 b = normalize(T * (ltc_vertex(i, k) - x));
        vec3 c = cross(a, b);
        F += ltc_theta_over_sin(dot(a, b), inversesqrt(max(dot(c, c), 1e-30))) * c;
        a = b;
    }
    vec3 c = cross(a, first);
    F += ltc_theta_over_sin(dot(a, first), inversesqrt(max(dot(c, c), 1e-30))) * c;
    F *= (dot(F, first) < 0.0 ? -0.5 : 0.5) * INV_PI;  // either winding: F points into the polygon
    return ltc_clipped_sphere(F);
}

// ∫ max(0, ω_z)/π dω over the spherical polygon of light i's vertices, transformed by T after subtracting x:
// (1/2π)|Σ θ_k Γ_k·z| over the polygon clipped to z ≥ 0 (Lambert's formula). With ``mixture`` and weight
// β: ∫ (1 − β) max(0, ω_z)/π + β W (n + 1)/(2π) max(0, ω_z)ⁿ, where the support window W is 0 when the
// polygon lies wholly outside the cone z ≥ LTC_CUT that holds all but LTC_CUT^(n+1) of the cosⁿ lobe (its
// highest point below the cut and the pole outside), else 1: the lobe ends there instead of fading as a power
// law. The absolute value makes either winding right, which is how a two-sided light seen from behind is
// handled. No local arrays (the vertices stream from the light records), no data-dependent branch (``mixture``
// is a constant at each call): this is what keeps it fast on SIMD rasterisers.
float ltc_polygon_integral(int i, int n, mat3 T, vec3 x, bool mixture, float weight) {
#if LTC_HORIZON == 1
#if LTC_POWER > 1
#error "the sphere horizon integrates the clamped cosine only"
#endif
    return ltc_polygon_integral_sphere(i, n, T, x);
#endif
    vec3 first = normalize(T * (ltc_vertex(i, 0) - x));
    vec3 a = first;
    vec3 exit_point = vec3(0.0), entry_point = vec3(0.0);
    vec2 sum = vec2(0.0);  // Σ θ Γ_z, Σ Γ_z Σ J_k
    vec3 support = vec3(0.0, 1e30, -1e30);  // highest z, least and greatest Γ_z
    for (int k = 1; k < n; ++k) {
        vec3 b = normalize(T * (ltc_vertex(i, k) - x));
        ltc_clipped_edge(a, b, mixture, sum, support, exit_point, entry_point);
        a = b;
    }
    ltc_clipped_edge(a, first, mixture, sum, support, exit_point, entry_point);
    // the horizon edge (0 when nothing was clipped); on it J_k = 0 for k > 0
    float horizon = cross(exit_point, entry_point).z;
    sum.x += ltc_edge(exit_point, entry_point);
#if LTC_POWER > 1
    if (mixture) {
        bool pole_inside = min(support.y, horizon) >= 0.0 || max(support.z, horizon) <= 0.0;
        float window = pole_inside || support.x >= LTC_CUT ? weight : 0.0;
        return abs((1.0 - weight) * sum.x + window * (sum.x + sum.y)) * (0.5 * INV_PI);
    }
#endif
    return abs(sum.x) * (0.5 * INV_PI);
}

// Per fragment, shared by all lights: world → (rotated local frame, view in the xz plane) → M⁻¹, and the
// lobe's magnitude.
bool g_ltc_ready = false;
mat3 g_ltc_transform;
vec3 g_ltc_lobe;
float g_ltc_weight;  // the mixture weight β of cosⁿ (0 for a clamped-cosine table)

// The polygon transform of a lobe about frame's normal at view wo (local to frame), table cell m = the four
// entries of M⁻¹: rows of (rotation about the normal bringing wo into the xz plane) · transpose(frame), in world
// space, times M⁻¹ = [[1, 0, m02], [0, m11, 0], [m20, 0, m22]] (rows).
mat3 ltc_transform(mat3 frame, vec3 wo, vec4 m) {
    float len2 = dot(wo.xy, wo.xy);
    vec2 c = len2 > 1e-14 ? wo.xy * inversesqrt(len2) : vec2(1.0, 0.0);
    vec3 r0 = c.x * frame[0] + c.y * frame[1];
    vec3 r1 = c.x * frame[1] - c.y * frame[0];
    vec3 n = frame[2];
    return transpose(mat3(r0 + m.x * n, m.y * r1, m.z * r0 + m.w * n));
}

#if LTC_FRAGMENT
// The material's parameters at this fragment (material_ibl, the split sum's hook: its textures read by
// material_surface): the Lambertian part's albedo — the dielectric's Fresnel-weighted diffuse lobe and a sheen
// as a Lambertian lobe of the sheen's albedo, their hemispherical averages at this view — and the GGX lobe's
// exact directional albedo (height-correlated Smith, Schlick: F0 A + B) over the family table's shape (the
// separable-Smith GGX fit) at the fragment's alpha; a clear coat as a second lobe about its own normal.
vec3 g_ltc_diffuse;
float ltc_roughness(float alpha) {
    return (sqrt(clamp(alpha, LTC_SQRT_ALPHA_MIN * LTC_SQRT_ALPHA_MIN, 1.0)) - LTC_SQRT_ALPHA_MIN) / (1.0 - LTC_SQRT_ALPHA_MIN);
}
#ifdef MATERIAL_COAT
mat3 g_ltc_coat_transform;
float g_ltc_coat_lobe;    // the coat's weight c F_c(v) × its lobe's albedo
float g_ltc_base_weight;  // 1 − c F_c(v): what the coat leaves of the base
#endif
#endif

void ltc_setup(mat3 frame, vec3 wo) {
#if LTC_FRAGMENT
    vec3 specular_albedo;
    float alpha;
    material_ibl(wo.z, g_ltc_diffuse, specular_albedo, alpha);
    vec2 uv = ltc_lookup(wo.z, ltc_roughness(alpha));
    vec4 m = texture(a_ltc_minv, uv);
    g_ltc_lobe = specular_albedo;
    g_ltc_weight = 0.0;
#ifdef MATERIAL_COAT
    float coat_weight, coat_alpha, coat_albedo;
    vec3 coat_n, v = frame * wo;
    material_coat_ibl(frame, v, coat_weight, coat_n, coat_alpha, coat_albedo);
    mat3 coat_frame = shading_frame(coat_n, vec4(frame[0], 1.0));  // any frame about n_c: ltc_transform turns it
    vec3 coat_wo = v * coat_frame;  // transpose(coat_frame) * v
    g_ltc_coat_transform = ltc_transform(coat_frame, coat_wo, texture(a_ltc_minv, ltc_lookup(coat_wo.z, ltc_roughness(coat_alpha))));
    g_ltc_coat_lobe = coat_weight * coat_albedo;
    g_ltc_base_weight = 1.0 - coat_weight;
#endif
#else
    vec2 uv = ltc_lookup(wo.z, a_ltc_roughness);
#if LTC_PROFILE == LTC_PROFILE_NO_FETCH
    vec4 m = vec4(0.0, 1.0, 0.0, 1.0) + uv.xyxy * 1e-3;  // keeps the lookup's arithmetic alive
    g_ltc_lobe = a_ltc_scale;
    g_ltc_weight = LTC_POWER > 1 ? 1.0 : 0.0;
#else
    vec4 m = texture(a_ltc_minv, uv);
    vec4 magnitude = texture(a_ltc_magnitude, uv);
    g_ltc_lobe = magnitude.rgb * a_ltc_scale;
    g_ltc_weight = magnitude.a;
#endif
#endif
    g_ltc_transform = ltc_transform(frame, wo, m);
    g_ltc_ready = true;
}

vec3 area_light_contribution(int i, vec3 x, mat3 frame, vec3 wo) {
#if LTC_PROFILE == LTC_PROFILE_FRAME_ONLY
    return vec3(0.0);
#endif
    vec4 head = ltc_light_row(i, 0);     // radiance, two-sided
    vec4 corner = ltc_light_row(i, 1);   // c1, vertex count
    vec3 normal = ltc_light_row(i, 4).xyz;
    float side = dot(x - corner.xyz, normal);  // as area_light_faces(): on an emitting side?
    if (!(head.w > 0.5 ? side != 0.0 : side > 0.0)) return vec3(0.0);
#if LTC_VERTICES > 0
    const int n = LTC_VERTICES;
#else
    int n = int(corner.w + 0.5);
#endif
    vec3 sum = vec3(0.0);
#if LTC_FRAGMENT
    if (!g_ltc_ready) ltc_setup(frame, wo);
    sum += g_ltc_diffuse * ltc_polygon_integral(i, n, transpose(frame), x, false, 0.0);
    sum += g_ltc_lobe * ltc_polygon_integral(i, n, g_ltc_transform, x, false, 0.0);
#ifdef MATERIAL_COAT
    sum = g_ltc_base_weight * sum + g_ltc_coat_lobe * ltc_polygon_integral(i, n, g_ltc_coat_transform, x, false, 0.0);
#endif
#else
#if LTC_DIFFUSE
    sum += a_ltc_diffuse * ltc_polygon_integral(i, n, transpose(frame), x, false, 0.0);
#endif
#if LTC_LOBE
    if (!g_ltc_ready) ltc_setup(frame, wo);
#if LTC_PROFILE == LTC_PROFILE_NO_EDGES
    sum += g_ltc_lobe * g_ltc_transform[0];  // the setup's results stay live; no polygon integral
#else
    sum += g_ltc_lobe * ltc_polygon_integral(i, n, g_ltc_transform, x, LTC_POWER > 1, g_ltc_weight);
#endif
#endif
#endif  // LTC_FRAGMENT
    return sum * head.rgb;
}
