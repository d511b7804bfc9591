// Provides the scratches shading pass for a scratched material: scratch_lobes.glsl's scratched_radiance at each
// fragment, seen from the camera.
#include BRDF
#define brdf_eval base_brdf_eval
#define material_ibl base_material_ibl
#define material_coat_ibl base_material_coat_ibl
#include "reflets/techniques/shaders/lights.glsl"
#undef brdf_eval
#undef material_ibl
#undef material_coat_ibl
#include "reflets/scratches/shaders/scratch_lobes.glsl"

in vec3 v_position;
in vec3 v_normal;
in vec4 v_tangent;
in vec2 v_uv;
in vec2 v_uv1;

uniform vec3 u_eye;

out vec4 f_color;

void main() {
    vec3 n = normalize(v_normal);
    if (!gl_FrontFacing) n = -n;
    mat3 frame = shading_frame(n, v_tangent);
#ifdef MATERIAL_SURFACE
    material_surface(vec4(v_uv, v_uv1), frame);  // a textured base (a glTF material): its textures into its parameters
    material_antialias(n);  // (no coverage test: the base is opaque, Scratched refuses cut-out and blended ones)
#endif
#if OUTPUT == 1
    f_color = vec4(v_position, 1.0);
#elif OUTPUT == 2
    f_color = vec4(n, 1.0);
#elif OUTPUT == 3
    f_color = vec4(v_uv, 0.0, 1.0);
#else
    vec3 wo = transpose(frame) * normalize(u_eye - v_position);
    vec3 radiance = scratched_radiance(v_position, frame, wo, v_uv, uvec2(gl_FragCoord.xy));
#ifdef MATERIAL_SURFACE
    radiance += material_emission();
#endif
    f_color = vec4(radiance, 1.0);
#endif
}
