// Provides point_visibility(i, x, n) and dir_visibility(i, x, n): the fraction of percentage-closer-filtered
// shadow-map texels that see point light i / directional light i from x (1: lit, 0: in shadow). Maps live in
// one depth atlas (reflets/techniques/shadows.py): six 90° views per point light, one orthographic view per
// directional light fitted to the scene; a light without shadows has view index -1 (always 1).
// SHADOW_VIEWS (compile-time) is the number of views; 0 compiles every test out.
#if SHADOW_VIEWS > 0
layout(std430, binding = 6) readonly buffer ShadowViews { vec4 shadow_data[]; };  // per view: mat4, tile, params
uniform sampler2DShadow u_shadow_atlas;

// PCF: 3×3 hardware-bilinear comparisons one texel apart (a 4×4-texel tent), clamped inside the view's tile.
float shadow_lookup(int view, vec3 x) {
    int base = 6 * view;
    mat4 m = mat4(shadow_data[base], shadow_data[base + 1], shadow_data[base + 2], shadow_data[base + 3]);
    vec4 clip = m * vec4(x, 1.0);
    vec3 ndc = clip.xyz / clip.w;
    if (clip.w <= 0.0 || any(greaterThan(abs(ndc), vec3(1.0)))) return 1.0;  // outside what the map holds: lit
    vec4 tile = shadow_data[base + 4];  // atlas uv of the tile's corner, its size
    vec2 texel = 1.0 / vec2(textureSize(u_shadow_atlas, 0));
    vec2 uv = tile.xy + (ndc.xy * 0.5 + 0.5) * tile.zw;
    float depth = ndc.z * 0.5 + 0.5;
    vec2 lo = tile.xy + 0.5 * texel, hi = tile.xy + tile.zw - 0.5 * texel;
    float lit = 0.0;
    for (int j = -1; j <= 1; ++j)
        for (int i = -1; i <= 1; ++i)
            lit += texture(u_shadow_atlas, vec3(clamp(uv + vec2(i, j) * texel, lo, hi), depth));
    return lit / 9.0;
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
    int view = int(point_data[2 * i + 1].w) - 1;
    if (view < 0) return 1.0;
    vec3 light = point_data[2 * i].xyz;
    vec3 d = x - light;
    vec3 a = abs(d);
    // the cube face by the major axis, in the order +x, −x, +y, −y, +z, −z (shadows.py)
    int face = a.x >= a.y && a.x >= a.z ? (d.x >= 0.0 ? 0 : 1) : a.y >= a.z ? (d.y >= 0.0 ? 2 : 3) : (d.z >= 0.0 ? 4 : 5);
    float major = max(a.x, max(a.y, a.z));
    float texel_size = shadow_data[6 * (view + face) + 5].x * major;  // a 90° view: 2 d / resolution
    vec3 wi = -d / max(length(d), 1e-20);
    vec3 p = normal_offset(x, n, wi, texel_size);
    vec3 dp = p - light;
    vec3 ap = abs(dp);
    face = ap.x >= ap.y && ap.x >= ap.z ? (dp.x >= 0.0 ? 0 : 1) : ap.y >= ap.z ? (dp.y >= 0.0 ? 2 : 3) : (dp.z >= 0.0 ? 4 : 5);
    return shadow_lookup(view + face, p);
}

float dir_visibility(int i, vec3 x, vec3 n) {
    int view = int(dir_data[2 * i + 1].w) - 1;
    if (view < 0) return 1.0;
    float texel_size = shadow_data[6 * view + 5].x;
    return shadow_lookup(view, normal_offset(x, n, dir_data[2 * i].xyz, texel_size));
}
#else
float point_visibility(int i, vec3 x, vec3 n) { return 1.0; }
float dir_visibility(int i, vec3 x, vec3 n) { return 1.0; }
#endif
