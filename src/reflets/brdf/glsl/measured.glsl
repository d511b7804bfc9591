// Provides brdf_eval(wo, wi) for the measured MERL material (twin of reflets/brdf/measured.py).
// m_table: x = φd (180 texels), y = θd (90), z = θh (90), RGB f_r with the channel scales applied. Coordinate
// = continuous MERL index / n, entry i at its texel centre (i + 0.5) / n; the trilinear interpolation of
// measured.py's NumPy reference (φd wraps, θd and θh clamp to the edge entries) is done here in float32 from
// eight texelFetch: a hardware texture unit filters with 8-bit weights (measured on an NVIDIA H200: 1e-2
// relative off the NumPy twin in steep parts of a table).
uniform sampler3D m_table;
uniform vec3 m_scale;

vec3 merl_entry(ivec3 i, ivec3 n) {
    i.x = i.x < 0 ? i.x + n.x : (i.x >= n.x ? i.x - n.x : i.x);  // φd is periodic
    i.yz = clamp(i.yz, ivec2(0), n.yz - 1);
    return texelFetch(m_table, i, 0).rgb;
}

vec3 merl_lookup(vec3 coord) {
    ivec3 n = textureSize(m_table, 0);
    vec3 p = coord * vec3(n) - 0.5;
    vec3 base = floor(p);
    vec3 f = p - base;
    ivec3 i = ivec3(base);
    vec3 c00 = mix(merl_entry(i, n), merl_entry(i + ivec3(1, 0, 0), n), f.x);
    vec3 c10 = mix(merl_entry(i + ivec3(0, 1, 0), n), merl_entry(i + ivec3(1, 1, 0), n), f.x);
    vec3 c01 = mix(merl_entry(i + ivec3(0, 0, 1), n), merl_entry(i + ivec3(1, 0, 1), n), f.x);
    vec3 c11 = mix(merl_entry(i + ivec3(0, 1, 1), n), merl_entry(i + ivec3(1, 1, 1), n), f.x);
    return mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z);
}

// atan(t) to ~2e-7 relative error (Cephes atanf). GLSL leaves atan's precision to the driver, and Mesa's
// llvmpipe is off by up to ~3e-6 rad, which shifts steep table regions by ~1e-3 relative; this keeps the
// coordinates within float rounding of the NumPy reference on every driver.
float merl_atan(float t) {
    float a = abs(t);
    float base = 0.0;
    float x = a;
    if (a > 2.414213562373095) {  // tan(3π/8)
        base = 0.5 * PI;
        x = -1.0 / a;
    } else if (a > 0.4142135623730950) {  // tan(π/8)
        base = 0.25 * PI;
        x = (a - 1.0) / (a + 1.0);
    }
    float z = x * x;
    float r = base + ((((8.05374449538e-2 * z - 1.38776856032e-1) * z + 1.99777106478e-1) * z
                       - 3.33329491539e-1) * z * x + x);
    return t < 0.0 ? -r : r;
}

vec3 brdf_eval(vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return vec3(0.0);
    vec3 s = wo + wi;
    vec3 u = wi - wo;  // = 2 sinθd (cosφd t + sinφd b): symmetric in (wo, wi) up to sign
    float s_len = length(s);
    vec3 h = s / s_len;  // h.z > 0 since wo.z, wi.z > 0
    float r = length(h.xy);
    float theta_h = merl_atan(r / h.z);
    float theta_d = merl_atan(length(u) / s_len);
    vec2 cs = r > 0.0 ? h.xy / r : vec2(1.0, 0.0);  // (cos φh, sin φh)
    float x = (u.x * cs.x + u.y * cs.y) * h.z - u.z * r;
    float y = u.y * cs.x - u.x * cs.y;
    // φd folded into [0, π) by reciprocity: atan2(y, x) mod π = atan(y / x) mod π
    float phi_d = x != 0.0 ? merl_atan(y / x) : (y != 0.0 ? 0.5 * PI : 0.0);
    if (phi_d < 0.0) phi_d += PI;
    vec3 coord = vec3(phi_d * INV_PI, theta_d * (2.0 * INV_PI), sqrt(theta_h * (2.0 * INV_PI)));
    return m_scale * merl_lookup(coord);
}
