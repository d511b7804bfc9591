// Provides scratched_radiance(x, frame, wo, uv, pixel): the radiance a scratched surface reflects towards wo
// (twin of reflets/scratches/shading.py):
//   L = max(0, 1 − ᾱ) · L_base + Σ_k α_k / max(ᾱ, 1) · L_k   (eq 3.4, ᾱ = Σ α_k, layers with α_k < 1e-6 culled)
// L_base: the base BRDF (base_brdf_eval) lit by lights.glsl's direct_lighting, which the includer defines over
// base_brdf_eval. L_k: layer k's scratch BRDF on its reflection half-cone — the environment importance-sampled
// with the table's CDF (eq 3.5, Fresnel weight ρ_s/ρ_m via the exact bin pdf), S_ENV_SAMPLES samples per frame
// split over the layers ∝ α_k (stratified); point / directional lights thickened (f_H, §3.7) with culling,
// S_LIGHT_SAMPLES per live layer. Used by the scratches pass and by the Fermat pass for reflected scratched
// meshes (the α maps are filtered with the footprint of the pixel that shows them, direct or reflected).
// Every loop is short (llvmpipe ends an invocation after 65,535 loop iterations): frames accumulate on the CPU.

uniform uint u_frame;
uniform uint u_seed;
uniform sampler2D s_table_a;  // (ρ_s(0).rgb, ρ_m) at [φ_out row, φ_in column]
uniform sampler2D s_table_b;  // (γ.rgb, pdf)
uniform sampler2D s_cdf;      // CDF of each φ_out row at the S_TABLE + 1 bin edges
uniform vec2 s_dir[S_LAYERS];  // (cos Θ_k, sin Θ_k): u_k in the tangent frame
uniform float s_thickness;     // H in radians
#if S_CONSTANT_ALPHA
uniform float s_coverage;
#else
uniform sampler2DArray s_alpha;  // α of layers 4p..4p+3 in layer p, mip-mapped
#endif
#if S_ENV_SAMPLES > 0
uniform sampler2D s_env;
uniform mat3 s_env_from_world;
#endif


const float HALF_PI = 1.57079632679489661923;
const float ALPHA_CULL = 1e-6;

float g_layer_alpha[S_LAYERS];

int phi_bin(float phi) {
    return clamp(int(floor((phi + HALF_PI) * float(S_TABLE) / PI)), 0, S_TABLE - 1);
}

// ρ_s(θ_o) = F_γ ρ_m + (1 − F_γ) ρ_s(0) at bins (b, j); x = 2|θ_o|/π. Also returns the bin's pdf.
vec3 rho_s(int b, int j, float x, out float pdf) {
    vec4 a = texelFetch(s_table_a, ivec2(j, b), 0);
    vec4 g = texelFetch(s_table_b, ivec2(j, b), 0);
    vec3 F = pow(vec3(max(x, 1e-30)), g.rgb);
    pdf = g.a;
    return F * a.a + (1.0 - F) * a.rgb;
}

// (θ, φ) of a local direction in layer k's cone frame.
vec2 cone_angles(vec3 w, vec2 d) {
    float wu = d.x * w.x + d.y * w.y;
    float wv = -d.y * w.x + d.x * w.y;
    return vec2(asin(clamp(wu, -1.0, 1.0)), atan(wv, w.z));
}

vec3 from_cone(float theta, float phi, vec2 d) {
    float st = sin(theta), ct = cos(theta);
    float sv = ct * sin(phi), cv = ct * cos(phi);
    return vec3(st * d.x - sv * d.y, st * d.y + sv * d.x, cv);
}

#if N_POINT > 0 || N_DIR > 0 || N_AREA > 0
// Σ_k α_k/max(ᾱ,1) L_k for one thickened light of irradiance E from local direction wl.
vec3 thick_light(vec3 wo, vec3 wl, vec3 E, float norm, inout uint rng) {
    float H = s_thickness;
    vec3 sum = vec3(0.0);
    for (int k = 0; k < S_LAYERS; ++k) {
        if (g_layer_alpha[k] <= 0.0) continue;
        vec2 o = cone_angles(wo, s_dir[k]);
        vec2 l = cone_angles(wl, s_dir[k]);
        float delta = l.x + o.x;
        if (abs(delta) >= H) continue;  // the cone misses the light's support (the document's culling)
        float half_width = sqrt(H * H - delta * delta);
        float lo = max(l.y - half_width, -HALF_PI), hi = min(l.y + half_width, HALF_PI);
        if (hi <= lo) continue;
        int b = phi_bin(o.y);
        float x = 2.0 * abs(o.x) / PI;
        float c = 3.0 / (PI * H * H * max(cos(l.x), sin(H)));
        float xi = rng_next(rng);
        vec3 acc = vec3(0.0);
        for (int i = 0; i < S_LIGHT_SAMPLES; ++i) {
            float phi = lo + (float(i) + xi) / float(S_LIGHT_SAMPLES) * (hi - lo);
            float dp = phi - l.y;
            float f = max(0.0, 1.0 - (delta * delta + dp * dp) / (H * H));
            float pdf;
            acc += rho_s(b, phi_bin(phi), x, pdf) * (cos(phi) * f * f);
        }
        sum += (g_layer_alpha[k] / norm) * acc * ((hi - lo) / float(S_LIGHT_SAMPLES) * c);
    }
    return sum * E;
}
#endif

// x: world position, frame: shading frame (columns t, b, n), wo: local direction to the eye, uv: texture
// coordinates (α maps), pixel: the random stream's pixel.
vec3 scratched_radiance(vec3 x, mat3 frame, vec3 wo, vec2 uv, uvec2 pixel) {
    // α of every layer first, outside any branch (the mip level comes from the pixel footprint's derivatives)
    float abar = 0.0;
    int last = 0;
    for (int p = 0; p < (S_LAYERS + 3) / 4; ++p) {
#if S_CONSTANT_ALPHA
        vec4 a4 = vec4(s_coverage);
#else
        vec4 a4 = texture(s_alpha, vec3(uv, float(p)));
#endif
        for (int c = 0; c < 4; ++c) {
            int k = 4 * p + c;
            if (k >= S_LAYERS) break;
            float a = a4[c] >= ALPHA_CULL ? a4[c] : 0.0;
            g_layer_alpha[k] = a;
            abar += a;
            if (a > 0.0) last = k;
        }
    }
    float norm = max(abar, 1.0);
    vec3 sum = max(0.0, 1.0 - abar) * direct_lighting(x, frame, wo);
    if (wo.z > 0.0 && abar > 0.0) {
        uint rng = rng_seed(pixel, u_frame, u_seed);
#if N_POINT > 0
        for (int i = 0; i < N_POINT; ++i) {
            vec3 d = point_data[POINT_STRIDE * i].xyz - x;
            float r2 = dot(d, d);
            float cone = point_cone(i, -d * inversesqrt(r2));
            if (cone <= 0.0) continue;  // outside a spot light's cone: no shadow lookup
            float v = cone * point_visibility(i, x, frame[2]);
            if (v <= 0.0) continue;
            sum += thick_light(wo, transpose(frame) * (d * inversesqrt(r2)), point_data[POINT_STRIDE * i + 1].rgb * (v / r2), norm, rng);
        }
#endif
#if N_DIR > 0
        for (int i = 0; i < N_DIR; ++i) {
            float v = dir_visibility(i, x, frame[2]);
            if (v <= 0.0) continue;
            sum += thick_light(wo, transpose(frame) * dir_data[2 * i].xyz, dir_data[2 * i + 1].rgb * v, norm, rng);
        }
#endif
#if N_AREA > 0
        // quad / polygon lights: each midpoint sample of the emitter (the forward pass's area_samples² per quad)
        // as a thickened light of irradiance L cosθ_y dA / r² — the lobes see the emitter as that many small
        // sources, smoothed by the thickening (documented approximation; converges as area_samples grows)
        for (int l = 0; l < N_AREA_LIGHTS; ++l) {  // each light's soft-shadow ratio once, then its samples
        float shadow = soft_visibility(u_area_runs[l].z, x, frame, wo);
        int first = int(u_area_runs[l].x + 0.5), end = first + int(u_area_runs[l].y + 0.5);
        for (int i = first; i < end; ++i) {
            vec4 p = area_data[3 * i];
            vec4 nl = area_data[3 * i + 1];
            vec3 d = p.xyz - x;
            float r2 = dot(d, d);
            vec3 wi = d * inversesqrt(r2);
            float cos_y = -dot(nl.xyz, wi);
            if (nl.w > 0.5) cos_y = abs(cos_y);
            if (cos_y <= 0.0) continue;
            sum += thick_light(wo, transpose(frame) * wi, area_data[3 * i + 2].rgb * (shadow * cos_y * p.w / r2), norm, rng);
        }
        }
#endif
#if S_ENV_SAMPLES > 0
        vec3 env = vec3(0.0);
        float xi = rng_next(rng);
        for (int i = 0; i < S_ENV_SAMPLES; ++i) {
            // the layer: stratified over the α-weighted layers (the budget split ∝ α_k)
            float target = (float(i) + xi) / float(S_ENV_SAMPLES) * abar;
            int k = 0;
            float cum = 0.0;
            for (int m = 0; m < S_LAYERS; ++m) {
                cum += g_layer_alpha[m];
                if (cum <= target) k = m + 1;
            }
            k = min(k, last);
            vec2 d = s_dir[k];
            vec2 o = cone_angles(wo, d);
            int b = phi_bin(o.y);
            // φ_in by exact inversion of row b's piecewise-linear CDF: binary search for max j with cdf[j] ≤ u
            float u = rng_next(rng);
            int lo = 0, hi = S_TABLE;
            for (int it = 0; it < S_LOG2; ++it) {
                if (hi - lo <= 1) break;
                int mid = (lo + hi) >> 1;
                if (texelFetch(s_cdf, ivec2(mid, b), 0).r <= u) lo = mid; else hi = mid;
            }
            float c0 = texelFetch(s_cdf, ivec2(lo, b), 0).r, c1 = texelFetch(s_cdf, ivec2(lo + 1, b), 0).r;
            float frac = c1 > c0 ? clamp((u - c0) / (c1 - c0), 0.0, 1.0) : 0.5;
            float phi = -HALF_PI + (float(lo) + frac) * PI / float(S_TABLE);
            float pdf;
            vec3 rho = rho_s(b, lo, 2.0 * abs(o.x) / PI, pdf);
            if (pdf <= 0.0) continue;
            vec3 wi = frame * from_cone(-o.x, phi, d);
            vec3 L = textureLod(s_env, equirect_uv(s_env_from_world * wi), 0.0).rgb;
            env += rho * (cos(phi) / pdf) * L;
        }
        sum += env * (abar / norm / float(S_ENV_SAMPLES));
#endif
    }
    return sum;
}
