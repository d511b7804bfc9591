// Provides the Fermat solve of a frame: each reflected vertex V's reflection point P seen from the eye, and whether
// the solver converged (w), written by transform feedback once per eye position — reflected.vert draws from them,
// so frames from the same camera (a persistent renderer's, a progressive method's) solve nothing.
#include "reflets/reflections/shaders/solver.glsl"

layout(location = 0) in vec3 in_position;

uniform vec3 u_eye;

out vec4 t_mirror;

void main() {
    FermatResult r = fermat_reflection(u_eye, in_position);
    t_mirror = vec4(r.position, r.converged ? 1.0 : 0.0);
    gl_Position = vec4(0.0, 0.0, 0.0, 1.0);
}
