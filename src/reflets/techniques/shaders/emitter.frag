// Provides emitter shading: the light's radiance on its emitting side(s), black behind a one-sided light;
// EMITTER_MASK: times the light's mask (nearest texel at the quad's (u, v), as every renderer reads it).
in vec2 v_uv;
uniform vec3 u_radiance;
uniform bool u_two_sided;
#if EMITTER_MASK
uniform sampler2D u_mask;
#endif
out vec4 f_color;
void main() {
    bool lit = gl_FrontFacing || u_two_sided;
    vec3 radiance = u_radiance;
#if EMITTER_MASK
    radiance *= texture(u_mask, v_uv).r;
#endif
    f_color = vec4(lit ? radiance : vec3(0.0), 1.0);
}
