// Provides brdf_eval(wo, wi) for the measured MERL material (twin of reflets/brdf/measured.py).
// m_table: x = φd (180 texels, REPEAT), y = θd (90, CLAMP_TO_EDGE), z = θh (90, CLAMP_TO_EDGE), LINEAR,
// RGB f_r with the channel scales applied. Texture coordinate = continuous MERL index / n, so entry i sits at
// its texel centre (i + 0.5) / n — the same trilinear interpolation as measured.py's NumPy reference.
uniform sampler3D m_table;
uniform vec3 m_scale;

vec3 brdf_eval(vec3 wo, vec3 wi) {
    if (wo.z <= 0.0 || wi.z <= 0.0) return vec3(0.0);
    vec3 s = wo + wi;
    vec3 u = wi - wo;  // = 2 sinθd (cosφd t + sinφd b): symmetric in (wo, wi) up to sign
    float s_len = length(s);
    vec3 h = s / s_len;
    float r = length(h.xy);
    float theta_h = atan(r, h.z);
    float theta_d = atan(length(u), s_len);
    vec2 cs = r > 0.0 ? h.xy / r : vec2(1.0, 0.0);  // (cos φh, sin φh)
    float x = (u.x * cs.x + u.y * cs.y) * h.z - u.z * r;
    float y = u.y * cs.x - u.x * cs.y;
    float phi_d = (x == 0.0 && y == 0.0) ? 0.0 : atan(y, x);
    if (phi_d < 0.0) phi_d += PI;  // reciprocity: φd and φd + π are the same entry
    vec3 coord = vec3(phi_d * INV_PI, theta_d * (2.0 * INV_PI), sqrt(theta_h * (2.0 * INV_PI)));
    return m_scale * textureLod(m_table, coord, 0.0).rgb;
}
