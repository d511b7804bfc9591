// Provides the forward shading pass: one BRDF (slot BRDF) lit by every light, or a geometry AOV (OUTPUT).
#include BRDF
#include "reflets/techniques/shaders/lights.glsl"
#include "reflets/techniques/shaders/transmission.glsl"

in vec3 v_position;
in vec3 v_normal;
in vec4 v_tangent;
in vec2 v_uv;
in vec2 v_uv1;

uniform vec3 u_eye;

out vec4 f_color;

void main() {
    vec3 n = normalize(v_normal);
    if (!gl_FrontFacing) n = -n;  // surfaces are two-sided: shade the side the camera sees
    mat3 frame = shading_frame(n, v_tangent);
#ifdef MATERIAL_SURFACE
    material_surface(vec4(v_uv, v_uv1), frame);  // textures into the parameters, the normal map into the frame
    material_antialias(n);         // sub-pixel highlights widened by the footprint's normals
    if (!material_covered()) discard;
#endif
#if OUTPUT == 1
    f_color = vec4(v_position, 1.0);
#elif OUTPUT == 2
    f_color = vec4(n, 1.0);
#elif OUTPUT == 3
    f_color = vec4(v_uv, 0.0, 1.0);
#else
    vec3 wo = transpose(frame) * normalize(u_eye - v_position);
    vec3 radiance = direct_lighting(v_position, frame, wo);
    float alpha = 1.0;
#ifdef MATERIAL_SURFACE
    radiance += material_emission();
    alpha = material_alpha();  // a blended surface: the weight of its radiance over what lies behind it
#endif
#if defined(BRDF_GLTF_TRANSMISSION) && BRDF_GLTF_TRANSMISSION
    radiance += transmitted_light(v_position, frame, wo);
#endif
    f_color = vec4(radiance, alpha);
#endif
}
