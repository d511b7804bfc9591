// Provides the solver alone for transform feedback: each input point V's reflection point seen from its eye, validity, iteration
// count and law-of-reflection residual (tests and benchmarks read them back per vertex).
#include "reflets/reflections/shaders/solver.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_eye;

out vec3 t_position;
out vec3 t_normal;
out float t_valid;
out float t_residual;
out float t_iterations;

void main() {
    FermatResult r = fermat_reflection(in_eye, in_position);
    t_position = r.position;
    t_normal = r.normal;
    t_valid = r.valid ? 1.0 : 0.0;
    t_residual = r.residual;
    t_iterations = float(r.iterations);
    gl_Position = vec4(0.0, 0.0, 0.0, 1.0);
}
