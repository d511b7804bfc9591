// Provides a compute kernel evaluating the BRDF in slot BRDF on arrays of (wo, wi): the GLSL/NumPy parity check.
#define COMPUTE_STAGE 1  // no screen derivatives here: material_antialias is left out
#include BRDF

layout(local_size_x = 64) in;
layout(std430, binding = 0) readonly buffer Outgoing { vec4 wo_data[]; };
layout(std430, binding = 1) readonly buffer Incoming { vec4 wi_data[]; };
layout(std430, binding = 2) writeonly buffer Values { vec4 f_data[]; };
uniform int u_count;

void main() {
    int i = int(gl_GlobalInvocationID.x);
    if (i >= u_count) return;
#ifdef MATERIAL_SURFACE
    mat3 frame = mat3(1.0);
    material_surface(vec4(0.5), frame);  // a textured material's parameters (its factors where no texture)
#endif
    f_data[i] = vec4(brdf_eval(wo_data[i].xyz, wi_data[i].xyz), 0.0);
}
