// Provides point_visibility(i, x, n) and dir_visibility(i, x, n): the fraction of percentage-closer-filtered
// shadow-map texels that see point light i / directional light i from x (1: lit, 0: in shadow); and
// soft_visibility(code, x, frame, wo), an area light's shadowed / unshadowed ratio over its sample views. Maps
// live in one depth atlas (reflets/techniques/shadows.py: views, records, the ratio estimator); a light without
// shadows has view index -1 / code 0 (always 1). SHADOW_VIEWS (compile-time) is the number of views; 0 compiles
// every test out.
#if SHADOW_VIEWS > 0
const int SHADOW_RECORD = 8;  // vec4 per view: mat4, tile, (texel), (sample point, weight), (axis)
layout(std430, binding = 6) readonly buffer ShadowViews { vec4 shadow_data[]; };
uniform sampler2DShadow u_shadow_atlas;
uniform sampler2D u_shadow_depth;  // the same atlas, raw depths (PCSS's blocker search)
uniform sampler2DShadow u_shadow_nearest;  // the same atlas, one comparison of the nearest texel

// x in view `view`'s map: the atlas uv and depth; false outside what the map holds.
bool shadow_coords(int view, vec3 x, out vec2 uv, out float depth, out vec4 tile) {
    int base = SHADOW_RECORD * view;
    mat4 m = mat4(shadow_data[base], shadow_data[base + 1], shadow_data[base + 2], shadow_data[base + 3]);
    vec4 clip = m * vec4(x, 1.0);
    vec3 ndc = clip.xyz / clip.w;
    if (clip.w <= 0.0 || any(greaterThan(abs(ndc), vec3(1.0)))) return false;
    tile = shadow_data[base + 4];  // atlas uv of the tile's corner, its size
    uv = tile.xy + (ndc.xy * 0.5 + 0.5) * tile.zw;
    depth = ndc.z * 0.5 + 0.5;
    return true;
}

// PCF: the mean of 3×3 hardware-bilinear comparisons one texel apart — per axis the texels t−1 … t+2 weighted
// (1 − f, 1, 1, f) / 3, f the sample's fraction between texel centres — taken as 2×2 bilinear comparisons: per
// axis one over (t−1, t) with weight 2 − f at fraction 1 / (2 − f) and one over (t+1, t+2) with weight 1 + f at
// fraction f / (1 + f) give the same weights (Castaño 2013's fitting of the taps). 4 lookups instead of 9: the
// point light of the helmet (reflets bench assets) cost 5 ms of a 26 ms llvmpipe frame with 9. Taps clamped
// inside the view's tile.
float shadow_lookup(int view, vec3 x) {
    vec2 uv;
    float depth;
    vec4 tile;
    if (!shadow_coords(view, x, uv, depth, tile)) return 1.0;  // outside what the map holds: lit
    vec2 size = vec2(textureSize(u_shadow_atlas, 0)), texel = 1.0 / size;
    vec2 lo = tile.xy + 0.5 * texel, hi = tile.xy + tile.zw - 0.5 * texel;
    vec2 p = uv * size - 0.5, t = floor(p), f = p - t;  // texel t's centre at (t + 0.5) / size
    vec2 w0 = 2.0 - f, w1 = 1.0 + f;                     // the two taps' weights per axis (sum 3)
    vec2 c0 = (t - 0.5 + 1.0 / w0) * texel, c1 = (t + 1.5 + f / w1) * texel;  // their positions
    float lit = w0.x * w0.y * texture(u_shadow_atlas, vec3(clamp(c0, lo, hi), depth))
              + w1.x * w0.y * texture(u_shadow_atlas, vec3(clamp(vec2(c1.x, c0.y), lo, hi), depth))
              + w0.x * w1.y * texture(u_shadow_atlas, vec3(clamp(vec2(c0.x, c1.y), lo, hi), depth))
              + w1.x * w1.y * texture(u_shadow_atlas, vec3(clamp(c1, lo, hi), depth));
    return lit / 9.0;
}

// One bilinear comparison (the soft shadows' views: the sum over sample views does the filtering).
float shadow_tap(int view, vec3 x) {
    vec2 uv;
    float depth;
    vec4 tile;
    if (!shadow_coords(view, x, uv, depth, tile)) return 1.0;
    vec2 texel = 1.0 / vec2(textureSize(u_shadow_atlas, 0));
    return texture(u_shadow_atlas, vec3(clamp(uv, tile.xy + 0.5 * texel, tile.xy + tile.zw - 0.5 * texel), depth));
}

// x moved off the surface along its normal (turned towards the light) by `texels` shadow texels of world size
// `texel_size`: the normal offset that keeps a lit surface out of its own shadow (no acne) without the large
// constant depth bias that detaches shadows from their casters (peter-panning).
vec3 normal_offset(vec3 x, vec3 n, vec3 wi, float texel_size) {
    float cos_t = dot(n, wi);
    vec3 nl = cos_t < 0.0 ? -n : n;
    float sin_t = sqrt(max(0.0, 1.0 - cos_t * cos_t));
    return x + nl * (texel_size * (0.5 + 1.5 * sin_t));  // grazing light: the slope, and the PCF reach, grow
}

float point_visibility(int i, vec3 x, vec3 n) {
    int view = int(point_data[POINT_STRIDE * i + 1].w) - 1;
    if (view < 0) return 1.0;
    vec3 light = point_data[POINT_STRIDE * i].xyz;
    vec3 d = x - light;
    vec3 a = abs(d);
    // the cube face by the major axis, in the order +x, −x, +y, −y, +z, −z (shadows.py)
    int face = a.x >= a.y && a.x >= a.z ? (d.x >= 0.0 ? 0 : 1) : a.y >= a.z ? (d.y >= 0.0 ? 2 : 3) : (d.z >= 0.0 ? 4 : 5);
    float major = max(a.x, max(a.y, a.z));
    float texel_size = shadow_data[SHADOW_RECORD * (view + face) + 5].x * major;  // a 90° view: 2 d / resolution
    vec3 wi = -d / max(length(d), 1e-20);
    vec3 p = normal_offset(x, n, wi, texel_size);
    vec3 dp = p - light;
    vec3 ap = abs(dp);
    face = ap.x >= ap.y && ap.x >= ap.z ? (dp.x >= 0.0 ? 0 : 1) : ap.y >= ap.z ? (dp.y >= 0.0 ? 2 : 3) : (dp.z >= 0.0 ? 4 : 5);
    return shadow_lookup(view + face, p);
}

// A directional light's views: its cascades (finest first) and the whole scene's (dir_data[2i].w of them); the
// finest that holds x with a margin for the filter and the normal offset serves.
float dir_visibility(int i, vec3 x, vec3 n) {
    int view = int(dir_data[2 * i + 1].w) - 1;
    if (view < 0) return 1.0;
    int last = view + int(dir_data[2 * i].w + 0.5) - 1;
    for (; view < last; ++view) {
        int base = SHADOW_RECORD * view;
        vec4 clip = mat4(shadow_data[base], shadow_data[base + 1], shadow_data[base + 2], shadow_data[base + 3]) * vec4(x, 1.0);
        float margin = 8.0 / (shadow_data[base + 4].z * float(textureSize(u_shadow_atlas, 0).x));  // 4 texels
        if (all(lessThan(abs(clip.xy), vec2(1.0 - margin)))) break;
    }
    float texel_size = shadow_data[SHADOW_RECORD * view + 5].x;
    return shadow_lookup(view, normal_offset(x, n, dir_data[2 * i].xyz, texel_size));
}
float linear_depth(float d, float near, float far) {
    float z = 2.0 * d - 1.0;
    return 2.0 * near * far / (far + near - z * (far - near));
}

// PCSS (Fernando 2005) from one view at the emitter's centre: the mean depth of the blockers found in the
// region the light's extent could hide x from, the penumbra width it implies (similar triangles: w_light
// (z_r − z_b) / z_b), and percentage-closer filtering over that width; 4 × 4 taps each.
float pcss_visibility(int view, vec3 x, vec3 n) {
    int base = SHADOW_RECORD * view;
    vec4 s = shadow_data[base + 6];
    vec3 axis = shadow_data[base + 7].xyz;
    vec4 lens = shadow_data[base + 5];  // texel size per unit depth, near, far
    vec3 d = x - s.xyz;
    float along = dot(d, axis);
    if (along <= 0.0) return 1.0;
    vec3 wi = -normalize(d);
    vec2 uv;
    float depth;
    vec4 tile;
    if (!shadow_coords(view, normal_offset(x, n, wi, lens.x * along), uv, depth, tile)) return 1.0;
    vec2 size = vec2(textureSize(u_shadow_atlas, 0));
    vec2 texel = 1.0 / size;
    vec2 lo = tile.xy + 0.5 * texel, hi = tile.xy + tile.zw - 0.5 * texel;
    float near = lens.y, far = lens.z;
    float z_r = linear_depth(depth, near, far);
    float width = lens.x * tile.z * size.x;  // tangent extent of the view (its uv per world unit at depth z: 1 / (z width))
    float light = sqrt(s.w);
    float search = min(light * (z_r - near) / (z_r * near * width), 0.125) * tile.z;  // atlas uv
    // receiver-plane bias: a blocker must be nearer than x's own tangent plane gets across the search region
    // (its world radius × tan of the surface's tilt to the light, tilt capped at 78°); without it a curved lit
    // surface finds itself as a blocker and darkens
    float cos_n = abs(dot(n, wi));
    float tilt = sqrt(max(0.0, 1.0 - cos_n * cos_n)) / max(cos_n, 0.2);
    float bias = max(2.0 * lens.x * z_r, search / tile.z * z_r * width * tilt);
    float blockers = 0.0, sum_z = 0.0;
    for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i) {
            vec2 o = (vec2(i, j) + 0.5) * 0.5 - 1.0;
            float z_b = linear_depth(texture(u_shadow_depth, clamp(uv + o * search, lo, hi)).r, near, far);
            if (z_b < z_r - bias) {
                blockers += 1.0;
                sum_z += z_b;
            }
        }
    if (blockers == 0.0) return 1.0;
    float z_b = sum_z / blockers;
    float radius = clamp(0.5 * light * (z_r - z_b) / (z_b * z_r * width) * tile.z, texel.x, 0.125 * tile.z);
    float lit = 0.0;
    for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i) {
            vec2 o = (vec2(i, j) + 0.5) * 0.5 - 1.0;
            lit += texture(u_shadow_atlas, vec3(clamp(uv + o * radius, lo, hi), depth));
        }
    return lit / 16.0;
}

// An area light's ratio estimator (Heitz et al. 2018): Σ w_k V_k / Σ w_k over its sample views, w_k = f cosθ_x
// cosθ_y dA / r² (luminance of f), V_k one comparison in view k. `code` packs (first view + 1) × 256 + points × 4
// + PCSS × 2 + (views per point − 1), 0 for a light without shadows (shadows.py writes it); a PCSS light has one
// view at its centre (two for a two-sided light).
float soft_visibility(float code, vec3 x, mat3 frame, vec3 wo) {
    int c = int(code + 0.5);
    if (c == 0) return 1.0;
    int first = (c >> 8) - 1, points = (c >> 2) & 63, per_point = (c & 1) + 1;
    if ((c & 2) != 0) {
        int view = first;
        if (per_point == 2 && dot(x - shadow_data[SHADOW_RECORD * view + 6].xyz, shadow_data[SHADOW_RECORD * view + 7].xyz) < 0.0)
            view += 1;
        return pcss_visibility(view, x, frame[2]);
    }
    vec3 n = frame[2];
    mat3 to_local = transpose(frame);
    float num = 0.0, den = 0.0;
    for (int k = 0; k < points; ++k) {
        int view = first + k * per_point;
        vec4 s = shadow_data[SHADOW_RECORD * view + 6];
        vec3 axis = shadow_data[SHADOW_RECORD * view + 7].xyz;
        vec3 d = x - s.xyz;  // from the light's point to x
        float dist = length(d);
        if (dist <= 0.0) continue;
        float along = dot(d, axis);
        if (per_point == 2 && along < 0.0) {  // a two-sided light: the view on x's side
            view += 1;
            along = -along;
        }
        vec3 wi = -d / dist;
        float cos_x = dot(n, wi);
        if (cos_x <= 0.0 || along <= 0.0) continue;
        vec3 f = brdf_eval(wo, to_local * wi);
        float w = (f.r + f.g + f.b) * cos_x * (along / dist) * s.w / (dist * dist);
        if (!(w > 0.0)) continue;
        float texel = shadow_data[SHADOW_RECORD * view + 5].x * along;
        num += w * shadow_tap(view, normal_offset(x, n, wi, texel));
        den += w;
    }
    return den > 0.0 ? num / den : 1.0;
}
// The environment's occlusion (ENV_VIEWS views, directions d_k drawn ∝ the map's power, weighted per channel):
// the visible fraction of the cosine-weighted light (`diffuse`) and of the light in the specular lobe
// (`specular`: a Phong lobe about the dominant direction r of the prefiltered lobe's width — the GGX α's — in
// place of the BRDF, which would cost an evaluation per direction; the diffuse fraction where the lobe misses
// every direction), per channel; one nearest-texel comparison per direction (the sum filters).
// Checkerboard (ENV_CHECKERBOARD: the techniques' `environment_occlusion`, on by default, where fine derivatives exist):
// the first ENV_FULL views (directions drawn more than once: a sun) are looked up at every fragment, the others
// alternately — a fragment looks up the half of its checkerboard parity and takes the other half's sums as the
// mean of its neighbours' across x and across y, read through fine derivatives within the 2×2 quad. Half the
// lookups; on the test floor the error against the reference is unchanged (a 2×2 quad-shared quarter made
// 2-pixel blocks). Needs every fragment of the quad alive: no discard before it.
#if ENV_VIEWS > 0
#if ENV_CHECKERBOARD && !defined(GL_ARB_derivative_control)  // a driver without fine derivatives: every lookup
#undef ENV_CHECKERBOARD
#define ENV_CHECKERBOARD 0
#endif
// per view k: rows 3k..3k+2 map (x, 1) to its atlas uv and depth (orthographic: affine); its direction and world
// texel size; its weight per channel; its tile's clamp box (shadows.py `environment_uniforms`)
uniform vec4 u_env_affine[3 * ENV_VIEWS];
uniform vec4 u_env_dir[ENV_VIEWS];
uniform vec4 u_env_rgb[ENV_VIEWS];
uniform vec4 u_env_box[ENV_VIEWS];

struct EnvSums {
    vec3 num_d, den_d, num_s, den_s;
};

void add_environment_view(int k, vec3 x, vec3 n, vec3 r, float exponent, inout EnvSums sums) {
    vec4 d = u_env_dir[k];
    float cos_x = dot(n, d.xyz);
    if (cos_x <= 0.0) return;
    vec3 w = u_env_rgb[k].rgb * cos_x;
    float lobe = pow(max(dot(r, d.xyz), 0.0), exponent);
    float sin_t = sqrt(max(0.0, 1.0 - cos_x * cos_x));
    vec4 p = vec4(x + n * (d.w * (0.5 + 1.5 * sin_t)), 1.0);  // normal_offset, n towards d
    vec4 box = u_env_box[k];
    vec2 uv = clamp(vec2(dot(u_env_affine[3 * k], p), dot(u_env_affine[3 * k + 1], p)), box.xy, box.zw);
    float v = texture(u_shadow_nearest, vec3(uv, dot(u_env_affine[3 * k + 2], p)));
    sums.num_d += w * v;
    sums.den_d += w;
    sums.num_s += w * (lobe * v);
    sums.den_s += w * lobe;
}

#if ENV_CHECKERBOARD
// the other half's sums at this fragment: the mean of its neighbours across x and across y (v ± dFdxFine(v))
vec3 other_half(vec3 v, vec2 sign) {
    return v + 0.5 * (sign.x * dFdxFine(v) + sign.y * dFdyFine(v));
}
#endif

void environment_visibility(vec3 x, vec3 n, vec3 r, float alpha, out vec3 diffuse, out vec3 specular) {
    float exponent = 0.5 / max(alpha * alpha, 1e-4) - 0.5;  // Blinn-Phong 2/α² − 2, a quarter about r
    EnvSums full = EnvSums(vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0));
    for (int k = 0; k < ENV_FULL; ++k) add_environment_view(k, x, n, r, exponent, full);
#if ENV_CHECKERBOARD
    vec2 odd = mod(floor(gl_FragCoord.xy), 2.0);
    EnvSums part = EnvSums(vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0));
    for (int k = ENV_FULL + int(mod(odd.x + odd.y, 2.0)); k < ENV_VIEWS; k += 2) add_environment_view(k, x, n, r, exponent, part);
    vec2 sign = 1.0 - 2.0 * odd;
    full.num_d += part.num_d + other_half(part.num_d, sign);
    full.den_d += part.den_d + other_half(part.den_d, sign);
    full.num_s += part.num_s + other_half(part.num_s, sign);
    full.den_s += part.den_s + other_half(part.den_s, sign);
#else
    for (int k = ENV_FULL; k < ENV_VIEWS; ++k) add_environment_view(k, x, n, r, exponent, full);
#endif
    diffuse = mix(vec3(1.0), full.num_d / max(full.den_d, vec3(1e-30)), greaterThan(full.den_d, vec3(0.0)));
    specular = mix(diffuse, full.num_s / max(full.den_s, vec3(1e-30)), greaterThan(full.den_s, 1e-12 * full.den_d));
}
#endif
#else
float point_visibility(int i, vec3 x, vec3 n) { return 1.0; }
float dir_visibility(int i, vec3 x, vec3 n) { return 1.0; }
float soft_visibility(float code, vec3 x, mat3 frame, vec3 wo) { return 1.0; }
#endif
