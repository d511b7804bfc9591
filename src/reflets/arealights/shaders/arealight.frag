// Provides the area-light shading pass: forward lighting for point / directional / environment lights plus,
// for every polygon light, the contribution of the method in slot AREA (area_light_contribution).
#include BRDF
#include "reflets/techniques/shaders/lights.glsl"
#include "reflets/techniques/shaders/transmission.glsl"
#include "reflets/arealights/shaders/polygon.glsl"
#include "reflets/arealights/shaders/material_lobe.glsl"
#include AREA

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
    material_surface(vec4(v_uv, v_uv1), frame);  // textures into the parameters, the normal map into the frame
    material_antialias(n);         // sub-pixel highlights widened by the footprint's normals
    if (!material_covered()) discard;
#endif
    vec3 wo = transpose(frame) * normalize(u_eye - v_position);
    vec3 sum = direct_lighting(v_position, frame, wo);
#ifdef MATERIAL_SURFACE
    sum += material_emission();
#endif
#if defined(BRDF_GLTF_TRANSMISSION) && BRDF_GLTF_TRANSMISSION
    sum += transmitted_light(v_position, frame, wo);
#endif
#if N_POLYGONS > 0
    for (int i = 0; i < N_POLYGONS; ++i) {
        vec3 light = area_light_contribution(i, v_position, frame, wo);
        float code = poly_data[i * POLY_STRIDE + 14].x;  // the light's soft shadows: the unshadowed × the ratio
        if (code > 0.0 && any(greaterThan(light, vec3(0.0)))) light *= soft_visibility(code, v_position, frame, wo);
        sum += light;
    }
#endif
#if OUTPUT == 4
    f_color = vec4(vec3(float(g_samples)), 1.0);
#elif defined(MATERIAL_SURFACE)
    f_color = vec4(sum, material_alpha());  // a blended surface: the weight of its radiance over what lies behind it
#else
    f_color = vec4(sum, 1.0);
#endif
}
