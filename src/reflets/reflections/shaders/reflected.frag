// Provides the reflected scene's fragments: visibility level 2 — the fragment must lie on this reflector's visible
// pixels (an exact id test, which also rejects what linear interpolation spills past the silhouette), its
// reflection point must not be behind the visible reflector surface (reflections on the hidden side), and the
// object point must lie in front of the mirror there (no reflection through the reflector) — then shading with
// the eye at the reflection point P (view-dependent materials look right in the mirror). REFLECTED_EMITTER: an
// area light. SCRATCHED: a scratched material, shaded as the scratches pass shades it (its lobes, with the α maps
// filtered by the footprint of the mirror pixel that shows them).
#if !REFLECTED_EMITTER
#include BRDF
// (#include inlines a file once, whatever the #if around it: lights.glsl is included in one place)
#if SCRATCHED
#define brdf_eval base_brdf_eval
#define material_ibl base_material_ibl
#define material_coat_ibl base_material_coat_ibl
#endif
#include "reflets/techniques/shaders/lights.glsl"
#if SCRATCHED
#undef brdf_eval
#undef material_ibl
#undef material_coat_ibl
#include "reflets/scratches/shaders/scratch_lobes.glsl"
#endif
#endif

in vec3 v_position;
in vec3 v_normal;
in vec4 v_tangent;
in vec2 v_uv;
in vec2 v_uv1;
in vec3 v_mirror_point;
in float v_valid;

uniform sampler2D u_gbuffer_position;
uniform sampler2D u_gbuffer_normal;
uniform float u_reflector_id;
uniform vec3 u_eye;
uniform float u_hidden_tolerance;  // world distance P may lie behind the visible surface (chord sag)
#if REFLECTED_EMITTER
uniform vec3 u_radiance;
uniform bool u_two_sided;
#endif
#if EMITTER_MASK
uniform sampler2D u_mask;  // the light's mask at the quad's (u, v) (nearest texel)
#endif

out vec4 f_color;

void main() {
    vec3 to_eye = v_mirror_point - v_position;
#if !REFLECTED_EMITTER
    vec3 n = normalize(v_normal);
    if (dot(n, to_eye) < 0.0) n = -n;  // two-sided surfaces, as seen from P
    mat3 frame = shading_frame(n, v_tangent);
#ifdef MATERIAL_SURFACE
    // a textured material, as in direct view — before any discard: implicit mip levels and the footprint's normals
    // need the whole 2x2 quad alive
    material_surface(vec4(v_uv, v_uv1), frame);
    material_antialias(n);
#endif
#endif
    if (v_valid < 0.9999) discard;  // a vertex without a valid reflection: the whole triangle goes
    vec4 g = texelFetch(u_gbuffer_position, ivec2(gl_FragCoord.xy), 0);
    if (abs(g.w - u_reflector_id) > 0.5) discard;
    if (length(v_mirror_point - u_eye) > length(g.xyz - u_eye) + u_hidden_tolerance) discard;
    if (dot(texelFetch(u_gbuffer_normal, ivec2(gl_FragCoord.xy), 0).xyz, v_position - g.xyz) <= 0.0) discard;
#if REFLECTED_EMITTER
    bool front = dot(v_normal, to_eye) > 0.0;
    vec3 radiance = u_radiance;
#if EMITTER_MASK
    radiance *= texture(u_mask, v_uv).r;
#endif
    f_color = vec4((front || u_two_sided) ? radiance : vec3(0.0), 1.0);
#else
#ifdef MATERIAL_SURFACE
    if (!material_covered()) discard;
#endif
    vec3 wo = transpose(frame) * normalize(to_eye);
#if SCRATCHED
    vec3 radiance = scratched_radiance(v_position, frame, wo, v_uv, uvec2(gl_FragCoord.xy));
#else
    vec3 radiance = direct_lighting(v_position, frame, wo);
#endif
#ifdef MATERIAL_SURFACE
    radiance += material_emission();
#endif
    f_color = vec4(radiance, 1.0);
#endif
}
