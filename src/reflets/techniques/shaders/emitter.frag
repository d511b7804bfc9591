// Provides emitter shading: the light's radiance on its emitting side(s), black behind a one-sided light.
uniform vec3 u_radiance;
uniform bool u_two_sided;
out vec4 f_color;
void main() {
    bool lit = gl_FrontFacing || u_two_sided;
    f_color = vec4(lit ? u_radiance : vec3(0.0), 1.0);
}
