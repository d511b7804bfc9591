// Provides the camera pass of the translucency technique for one translucent material (slot BRDF =
// translucent.glsl): the interface's specular reflection of the light (shadowed through the light view), single
// scattering by a ray march along the refracted view ray, and multiple scattering by the ring integral of the
// diffusion profile over the light view (reflets/translucency/technique.py explains each term).
// Flags: LIGHT_DIRECTIONAL, PROFILE, SS_NODES (k_max + 1), RINGS, ANGLES, TERMS (bit 1 specular, 2 single,
// 4 multiple), MS_PRODUCT (1: product integration, 0: the document's bilinear cells), VIEW_BLEND (the
// document's light-/camera-view blend), CURVATURE_REJECTION (the document's rejection of nodes past a fold),
// REFRACTION (1: image-space two-surface refraction through the back-face maps; 2: its exit point as output),
// RING_SETS (1: one ring layout for the three channels; 3: one per channel, each integral keeping its channel).
#include BRDF
#include "reflets/translucency/shaders/profiles.glsl"

in vec3 v_position;
in vec3 v_normal;
in vec4 v_tangent;
in vec2 v_uv;
in vec2 v_uv1;

uniform vec3 u_eye;
uniform mat4 u_light_view_proj;
uniform sampler2D u_light_position;  // world position of the lit surface, w = 1 where there is one
uniform sampler2D u_light_normal;
uniform vec3 u_light_vector;         // directional: unit vector towards the light; point: its position
uniform vec3 u_light_power;          // directional: irradiance on a plane facing it; point: intensity
uniform float u_shadow_bias;         // scene units: how far the lit surface may lie from the shaded point

uniform vec3 a_sigma_s;              // 1/mm
uniform vec3 a_sigma_t;              // 1/mm
uniform float a_g;
uniform float a_mm_per_unit;
uniform vec3 a_diffuse_norm;         // 1 / (π (1 − 2 C1_out))
uniform float a_ss_depth[SS_NODES];  // march depths in mean free paths 1/σ_t
uniform float a_ss_weight[SS_NODES]; // their quadrature weights (same units)
// Ring set k's node j at index k (RINGS + 1) + j:
uniform float a_ring_radius[(RINGS + 1) * RING_SETS];  // scene units
uniform vec3 a_ring_weight[(RINGS + 1) * RING_SETS];   // per node of ring j (bilinear: mm², the centre counting
                                                       // ANGLES copies; product: ∫ R_d ρ hat_j dρ dθ over ρ > ρ₁)
uniform vec3 a_ring_inv_rd[(RINGS + 1) * RING_SETS];   // product: 1 / R_d(ρ_j)

out vec4 f_color;

vec3 to_light(vec3 x) {
#if LIGHT_DIRECTIONAL
    return u_light_vector;
#else
    return normalize(u_light_vector - x);
#endif
}

vec3 light_irradiance(vec3 x) {
#if LIGHT_DIRECTIONAL
    return u_light_power;
#else
    vec3 d = u_light_vector - x;
    return u_light_power / dot(d, d);
#endif
}

// Distance from p back to the lit surface point xi along the light ray: a difference of distances to the light
// (a depth map's measure), which the map's lateral quantisation does not bias as |p − xi| would.
float light_distance(vec3 p, vec3 xi) {
#if LIGHT_DIRECTIONAL
    return max(dot(xi - p, u_light_vector), 0.0);
#else
    return max(length(u_light_vector - p) - length(u_light_vector - xi), 0.0);
#endif
}

// The first surface along the light ray through p: its position and normal (false if none).
// The surface a view's position / normal maps hold along its ray through p (false if none).
bool map_lookup(mat4 view_proj, sampler2D positions, sampler2D normals, vec3 p, out vec3 xi, out vec3 ni) {
    vec4 clip = view_proj * vec4(p, 1.0);
    xi = vec3(0.0);
    ni = vec3(0.0, 0.0, 1.0);
    if (clip.w <= 0.0) return false;
    vec2 uv = clip.xy / clip.w * 0.5 + 0.5;
    if (any(lessThan(uv, vec2(0.0))) || any(greaterThan(uv, vec2(1.0)))) return false;
    vec4 a = textureLod(positions, uv, 0.0);
    xi = a.xyz;
    ni = textureLod(normals, uv, 0.0).xyz;
    return a.w > 0.5;
}

bool light_lookup(vec3 p, out vec3 xi, out vec3 ni) {
    return map_lookup(u_light_view_proj, u_light_position, u_light_normal, p, xi, ni);
}

// The shadow-map tolerance at a surface point of normal n: the map's texel-scale bias stretched by the slope
// tan θ_l of the surface as the light sees it (at grazing light one texel spans a long stretch of depth, and
// a fixed bias leaves streaks of false shadow along the terminator).
float shadow_tolerance(vec3 x, vec3 n) {
    float c = clamp(abs(dot(n, to_light(x))), 0.03, 1.0);
    return u_shadow_bias * max(1.0, sqrt(1.0 - c * c) / c);
}

// Whether the light sees x (normal n) itself: the map's surface along the light ray through x lies no further
// in front of x than the tolerance (a one-sided shadow-map test). Where the light grazes a surface its nearest
// texel may hold the background or the surface beyond the silhouette (false shadow in teeth along the
// terminator): then a neighbouring texel that holds x's own surface, close to x, decides.
bool sees_light(vec3 x, vec3 n, out vec3 xi, out vec3 ni) {
    float tolerance = shadow_tolerance(x, n);
    if (light_lookup(x, xi, ni) && light_distance(x, xi) < tolerance) return true;
    vec4 clip = u_light_view_proj * vec4(x, 1.0);
    if (clip.w <= 0.0) return false;
    vec2 uv = clip.xy / clip.w * 0.5 + 0.5;
    vec2 texel = 1.0 / vec2(textureSize(u_light_position, 0));
    for (int k = 0; k < 9; ++k) {
        if (k == 4) continue;  // the centre, tried above
        vec2 q = uv + vec2(float(k % 3 - 1), float(k / 3 - 1)) * texel;
        vec4 a = textureLod(u_light_position, q, 0.0);
        if (a.w > 0.5 && light_distance(x, a.xyz) < tolerance && length(a.xyz - x) < 2.0 * tolerance) {
            xi = a.xyz;
            ni = textureLod(u_light_normal, q, 0.0).xyz;
            return true;
        }
    }
    return false;
}

float hg_phase(float cos_theta, float g) {
    float d = 1.0 + g * g - 2.0 * g * cos_theta;
    return (1.0 - g * g) / (4.0 * PI * d * sqrt(d));
}

// Light entering at xi (normal ni): transmitted flux density along the refracted beam, F_T E⊥ μ/μ', and the
// refracted direction of travel; false when the light does not reach xi's outside.
bool entering(vec3 xi, vec3 ni, out vec3 beam, out vec3 travel, out float cos_ratio) {
    vec3 wl = to_light(xi);
    float mu = dot(ni, wl);
    beam = vec3(0.0);
    travel = -ni;
    cos_ratio = 1.0;
    if (mu <= 0.0) return false;
    float mu_t = sqrt(max(1.0 - (1.0 - mu * mu) / (m_eta * m_eta), 1e-12));
    travel = refract(-wl, ni, 1.0 / m_eta);
    cos_ratio = mu / mu_t;
    beam = (1.0 - fresnel_dielectric(mu, m_eta)) * light_irradiance(xi);
    return true;
}

uniform float a_ss_c_l;               // march depth in mean free paths (c_l)
uniform float a_ss_step;              // 1: the document's step rule, 0: trapezoid

// Depth k of the march when the medium ends c mean free paths down the refracted ray (c < c_l): the same
// truncated exponential up to c, with the rule's weights (the uniform tables hold the c = c_l case).
float march_depth(int k, float c) {
    return -log(max(1.0 - (1.0 - exp(-c)) * float(k) / float(SS_NODES - 1), 1e-30));
}

float march_weight(int k, float c) {
    float here = march_depth(k, c);
    float before = k > 0 ? march_depth(k - 1, c) : here;
    float after = k < SS_NODES - 1 ? march_depth(k + 1, c) : here;
    return a_ss_step > 0.5 ? here - before : 0.5 * (after - before);
}

// s_exit: mm along the refracted view ray to where it leaves the object (1e30: unknown, the half-space case).
vec3 single_scattering(vec3 x, vec3 n, vec3 wo, float s_exit) {
    vec3 t_o = refract(-wo, n, 1.0 / m_eta);  // the view ray inside the medium
    vec3 sum = vec3(0.0);
    for (int c = 0; c < 3; ++c) {
        float sigma_t = a_sigma_t[c];
        float c_end = min(a_ss_c_l, sigma_t * s_exit);  // in mean free paths
        bool clipped = c_end < a_ss_c_l;
        float total = 0.0;
        for (int k = 0; k < SS_NODES; ++k) {
            float depth = clipped ? march_depth(k, c_end) : a_ss_depth[k];
            float weight = clipped ? march_weight(k, c_end) : a_ss_weight[k];
            float s = depth / sigma_t;  // mm along the refracted view ray
            vec3 p = x + t_o * (s / a_mm_per_unit);
            vec3 xi, ni;
            if (!light_lookup(p, xi, ni)) continue;
            // p outside, in front of the lit surface (beyond the map's quantisation: p = x at k = 0 is on it)
            if (dot(p - xi, to_light(xi)) > u_shadow_bias) continue;
            vec3 beam, travel;
            float cos_ratio;
            if (!entering(xi, ni, beam, travel, cos_ratio)) continue;
            float s_line = light_distance(p, xi) * a_mm_per_unit;
            float s_refracted = s_line * cos_ratio;  // the document's Snell correction of the light's path
            float phase = hg_phase(dot(travel, -t_o), a_g);
            total += weight / sigma_t * phase * beam[c] * cos_ratio * exp(-sigma_t * (s_refracted + s));
        }
        sum[c] = a_sigma_s[c] * total;
    }
    return sum * (1.0 - fresnel_dielectric(dot(n, wo), m_eta)) / (m_eta * m_eta);
}

#if VIEW_BLEND || REFRACTION
uniform mat4 u_view_proj;            // the camera's (shared with the vertex stage)
#endif

#if REFRACTION
uniform sampler2D u_back_position;   // the nearest back face of a translucent mesh per pixel (w = 1: one)
uniform sampler2D u_back_normal;     // its outward normal
uniform vec3 u_background;           // radiance behind the object (the scene's constant background)

// Where the refracted view ray t from x (normal n, seen from wo) leaves the object: Wyman's two-surface
// approximation. The back face behind x on the camera ray is d_V away; taking the back surface parallel to the
// front one (his distance along the normal d_N ≈ d_V cos θ_o) gives the first estimate along t,
// d_V cos θ_o / cos θ_t; it is refined by intersecting t with the tangent plane of the back face seen where
// the estimate projects (exact on a flat back face), stepping back when the estimate leaves the map.
bool refracted_exit(vec3 x, vec3 n, vec3 wo, vec3 t, out vec3 xe, out vec3 ne) {
    vec3 xb, nb;
    xe = x;
    ne = -t;
    if (!map_lookup(u_view_proj, u_back_position, u_back_normal, x, xb, nb)) return false;
    float d = length(xb - x) * dot(n, wo) / max(dot(-n, t), 0.05);
    bool found = false;
    for (int i = 0; i < 6; ++i) {
        if (!map_lookup(u_view_proj, u_back_position, u_back_normal, x + t * d, xb, nb)) {
            d *= 0.5;
            continue;
        }
        float facing = dot(t, nb);
        if (facing < 1e-3) return false;  // the ray runs along the back surface there
        float next = dot(xb - x, nb) / facing;
        if (next <= 0.0) return false;
        found = abs(next - d) < 1e-4 * next;
        d = next;
        if (found) break;
    }
    if (!found && !map_lookup(u_view_proj, u_back_position, u_back_normal, x + t * d, xb, nb)) return false;
    xe = x + t * d;
    ne = nb;
    return true;
}

// The background seen through the object along the twice-refracted ray, attenuated by the unscattered
// transmittance e^{−σ_t s} (scattered light is the other terms'; the document's e^{−σ_a s} holds for a clear
// medium) and the two Fresnel transmittances; the η² of entering and the 1/η² of leaving cancel. Total
// internal reflection at the exit: none (the reflected ray is not followed).
vec3 transmitted(vec3 x, vec3 n, vec3 wo, vec3 t, vec3 xe, vec3 ne) {
    vec3 out_dir = refract(t, -ne, m_eta);
    if (dot(out_dir, out_dir) < 0.5) return vec3(0.0);
    float s = length(xe - x) * a_mm_per_unit;
    float ft = (1.0 - fresnel_dielectric(dot(n, wo), m_eta)) * (1.0 - fresnel_dielectric(dot(t, ne), 1.0 / m_eta));
    return u_background * ft * exp(-a_sigma_t * s);
}
#endif

#if VIEW_BLEND
uniform sampler2D u_camera_position; // the camera's own position / normal maps (w = 1 where a surface is seen)
uniform sampler2D u_camera_normal;
uniform float a_blend_lambda;

bool camera_lookup(vec3 p, out vec3 xc, out vec3 nc) {
    return map_lookup(u_view_proj, u_camera_position, u_camera_normal, p, xc, nc);
}
#endif

// One ring node of the light view (view 0): the flux density entering the surface point the light sees
// through p, per unit area of the plane orthogonal to the light. Of the camera view (view 1, the document's
// blend): the surface point the camera sees through p, its flux density per unit area of the plane
// orthogonal to the view (lit if the light map holds that point: E F_T cosθ_l / cosθ_o). r: true distance
// (mm) from x; xs, ns: the surface point and its normal (surface: whether the view holds one through p).
vec3 ring_node(int view, vec3 x, vec3 p, out float r, out vec3 xs, out vec3 ns, out bool surface) {
    vec3 beam, travel;
    float cos_ratio;
    r = 0.0;
#if VIEW_BLEND
    if (view == 1) {
        vec3 xl, nl;
        surface = camera_lookup(p, xs, ns);
        if (!surface || !sees_light(xs, ns, xl, nl)) return vec3(0.0);
        if (!entering(xs, ns, beam, travel, cos_ratio)) return vec3(0.0);
        r = length(xs - x) * a_mm_per_unit;
        float cos_l = dot(ns, to_light(xs));
        float cos_o = max(dot(ns, normalize(u_eye - xs)), 0.05);
        return beam * profile_incidence(cos_l) * cos_l / cos_o;
    }
#endif
    surface = light_lookup(p, xs, ns);
    if (!surface || !entering(xs, ns, beam, travel, cos_ratio)) return vec3(0.0);
    r = length(xs - x) * a_mm_per_unit;
    return beam * profile_incidence(dot(ns, to_light(xs)));
}

#if CURVATURE_REJECTION
uniform float a_curvature_max;  // 1/mm: κ above which a spoke of the ring integral stops

// The document's curvature rejection: along a spoke (the nodes of one direction, centre outwards) the discrete
// curvature between consecutive surface points, κ = angle(n_prev, n) / |x − x_prev|; once it exceeds κ_max the
// spoke has crossed an edge or a fold onto another surface, and this node and those beyond it are dropped.
bool spoke_continues(vec3 x_prev, vec3 n_prev, vec3 xs, vec3 ns) {
    float turn = acos(clamp(dot(n_prev, ns), -1.0, 1.0));
    return turn <= a_curvature_max * length(xs - x_prev) * a_mm_per_unit;
}
#endif

const float GAUSS3_T[3] = float[3](0.1127016654, 0.5, 0.8872983346);  // Gauss-Legendre on [0, 1]
const float GAUSS3_W[3] = float[3](0.2777777778, 0.4444444444, 0.2777777778);

// The profile integrated around x (normal n) over the light view (view 0) or the camera view (view 1) with
// ring set `ring_set`, spoke by spoke (one direction at a time, centre outwards, so that curvature rejection
// can cut a spoke).
vec3 profile_integral(int view, vec3 x, vec3 n, vec3 wo, int ring_set) {
    int k0 = ring_set * (RINGS + 1);
    vec3 axis = view == 0 ? to_light(x) : wo;
    mat3 basis = shading_frame(axis, vec4(0.0));  // columns: two axes of the plane orthogonal to the view
    vec3 sum = vec3(0.0);
    float rho1 = a_ring_radius[k0 + 1] * a_mm_per_unit;  // mm
    // The centre: where the light enters along its line through x, r_c measured along that line (0 where the
    // light sees x — |xi − x| would add the light map's lateral quantisation, which a sharp profile feels).
    float r_c;
    vec3 xs_c, ns_c;
    bool surface_c;
    vec3 beam_c = ring_node(view, x, x, r_c, xs_c, ns_c, surface_c);
    vec3 xi_c, ni_c;
    if (view == 1) {
        r_c = 0.0;  // the camera sees x itself
    } else if (sees_light(x, n, xi_c, ni_c)) {
        r_c = 0.0;
        if (!surface_c) {  // found in a neighbouring texel (light grazing x): the light enters at x
            vec3 travel;
            float cos_ratio;
            xs_c = xi_c;
            ns_c = ni_c;
            surface_c = entering(xs_c, ns_c, beam_c, travel, cos_ratio);
            beam_c *= profile_incidence(dot(ns_c, to_light(xs_c)));
        }
    } else if (surface_c) {
        r_c = light_distance(x, xs_c) * a_mm_per_unit;  // through the medium, from where the light enters
    }
    vec3 first_cell = vec3(0.0);                     // product rule: Σ_a ∫₀^ρ₁ R_d(r_a(ρ)) ρ dρ
    for (int a = 0; a < ANGLES; ++a) {
        float theta = TWO_PI * float(a) / float(ANGLES);
        vec3 dir = cos(theta) * basis[0] + sin(theta) * basis[1];
#if CURVATURE_REJECTION
        vec3 x_prev = surface_c ? xs_c : x;
        vec3 n_prev = surface_c ? ns_c : axis;
        bool alive = true;
#endif
        for (int j = 1; j <= RINGS; ++j) {
            vec3 p = x + a_ring_radius[k0 + j] * dir;
            float r;
            vec3 xs, ns;
            bool surface;
            vec3 beam = ring_node(view, x, p, r, xs, ns, surface);
#if CURVATURE_REJECTION
            if (surface && alive) {
                alive = spoke_continues(x_prev, n_prev, xs, ns);
                x_prev = xs;
                n_prev = ns;
            }
            if (!alive) beam = vec3(0.0);
#endif
#if MS_PRODUCT
            // R_d at the true distance relative to the plane distance's, which the weights integrate
            sum += a_ring_weight[k0 + j] * beam * profile_rd(r) * a_ring_inv_rd[k0 + j];
            if (j == 1) {
                // Inside the first ring the true distance is modelled as r(ρ)² = r_c² + k² ρ², k fitted to this
                // direction's node (k ≥ 1: true distances are never shorter than the plane's), and the light
                // varies linearly from the centre's to the node's (none beyond a silhouette). The integral
                // ∫₀^ρ₁ R_d(r(ρ)) ρ dρ = (C(r(ρ₁)) − C(r_c)) / k² is exact (C the profile's cumulative); how it
                // splits between the centre's and the node's light comes from a 3-point Gauss rule.
                float r1 = r > 0.0 ? r : sqrt(r_c * r_c + rho1 * rho1);  // node unlit: assume k = 1
                float k2 = max((r1 * r1 - r_c * r_c) / (rho1 * rho1), 1.0);
                vec3 total = (profile_cumulative(sqrt(r_c * r_c + k2 * rho1 * rho1)) - profile_cumulative(r_c)) / k2;
                vec3 inner = vec3(0.0), outer = vec3(0.0);
                for (int g = 0; g < 3; ++g) {
                    float t = GAUSS3_T[g];
                    vec3 f = GAUSS3_W[g] * t * profile_rd(sqrt(r_c * r_c + k2 * t * t * rho1 * rho1));
                    inner += f * (1.0 - t);
                    outer += f * t;
                }
                vec3 share = outer / max(inner + outer, vec3(1e-30));
                first_cell += total * ((1.0 - share) * beam_c + share * beam);
            }
#else
            sum += a_ring_weight[k0 + j] * beam * profile_rd(r);
#endif
        }
    }
#if MS_PRODUCT
    // The first cell (ρ < ρ₁) holds most of a sharp profile's energy (normalised diffusion is singular at 0):
    // integrated per direction above.
    sum += (TWO_PI / float(ANGLES)) * first_cell;
#else
    sum += beam_c * profile_rd(r_c) * a_ring_weight[k0] * float(ANGLES);
#endif
    return sum;
}

// The integral with the shared ring set, or each channel's with its own set.
vec3 view_integral(int view, vec3 x, vec3 n, vec3 wo) {
#if RING_SETS == 3
    return vec3(profile_integral(view, x, n, wo, 0).r, profile_integral(view, x, n, wo, 1).g,
                profile_integral(view, x, n, wo, 2).b);
#else
    return profile_integral(view, x, n, wo, 0);
#endif
}

vec3 multiple_scattering(vec3 x, vec3 n, vec3 wo) {
    vec3 sum = view_integral(0, x, n, wo);
#if VIEW_BLEND
    // The document's blend: the light view where the light meets the surface squarely, the camera view where
    // the camera does (s = 1/(1 + e^{−λ((n·ω_l) − (n·ω_o))})).
    float s = 1.0 / (1.0 + exp(-a_blend_lambda * (dot(n, to_light(x)) - dot(n, wo))));
    sum = s * sum + (1.0 - s) * view_integral(1, x, n, wo);
#endif
    return sum * a_diffuse_norm * (1.0 - fresnel_dielectric(dot(n, wo), m_eta));
}

void main() {
    vec3 n = normalize(v_normal);
    if (!gl_FrontFacing) n = -n;
    vec3 x = v_position;
    vec3 wo = normalize(u_eye - x);
    vec3 color = vec3(0.0);
#ifdef MATERIAL_SURFACE
    mat3 surface_frame = shading_frame(n, v_tangent);
    material_surface(vec4(v_uv, v_uv1), surface_frame);  // the albedo map's texel here, where the light leaves
#endif
#if (TERMS & 1) != 0
    vec3 wl = to_light(x);
    vec3 xi, ni;
    bool lit = sees_light(x, n, xi, ni);
    float cos_l = dot(n, wl);
    if (lit && cos_l > 0.0 && dot(n, wo) > 0.0) {
        mat3 frame = shading_frame(n, v_tangent);
        color += vec3(tr_specular(transpose(frame) * wo, transpose(frame) * wl)) * light_irradiance(x) * cos_l;
    }
#endif
    float s_exit = 1e30;  // mm along the refracted view ray to the back surface
#if REFRACTION
    vec3 t_in = refract(-wo, n, 1.0 / m_eta);
    vec3 xe, ne;
    bool exits = dot(n, wo) > 0.0 && refracted_exit(x, n, wo, t_in, xe, ne);
    if (exits) s_exit = length(xe - x) * a_mm_per_unit;
#endif
    vec3 leaving = vec3(0.0);  // the light leaving the medium at x: × the albedo map
#if (TERMS & 2) != 0
    leaving += single_scattering(x, n, wo, s_exit);
#endif
#if (TERMS & 4) != 0
    leaving += multiple_scattering(x, n, wo);
#endif
#if REFRACTION && (TERMS & 8) != 0
    if (exits) leaving += transmitted(x, n, wo, t_in, xe, ne);
#endif
    color += leaving * tr_albedo();
#if REFRACTION == 2
    color = exits ? xe : vec3(0.0);  // the exit point as output (tests)
#endif
#if OUTPUT == 1
    color = x;  // the geometry AOVs, as forward.frag writes them
#elif OUTPUT == 2
    color = n;
#elif OUTPUT == 3
    color = vec3(v_uv, 0.0);
#endif
    f_color = vec4(color, 1.0);
}
