// Provides the last pass of the fermat method: on the pixels of one reflector, add reflectance (its maps read at
// the pixel's uv) × the reflected radiance (the reflected scene where it was drawn, else the background along the
// mirror direction — exact for an environment at infinity). Blended additively onto the image that already holds
// the non-specular part.
// A full-screen pass: the uvs come from the G-buffer, whose neighbours' differences (a uv seam, a silhouette) are no
// footprint, so a mapped reflectance is read at the base level (the pixel's supersampling filters it).
#define MAP_TEXTURE(s, p) textureLod(s, p, 0.0)
#include BRDF

in vec2 v_ndc;

uniform sampler2D u_gbuffer_position;
uniform sampler2D u_gbuffer_normal;
uniform sampler2D u_gbuffer_uvs;
uniform sampler2D u_reflection;
uniform float u_reflector_id;
uniform vec3 u_eye;
#if BACKGROUND_ENV
uniform sampler2D u_env;
uniform mat3 u_env_from_world;
#else
uniform vec3 u_background;
#endif

out vec4 f_color;

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    vec4 g = texelFetch(u_gbuffer_position, pixel, 0);
    if (abs(g.w - u_reflector_id) > 0.5) discard;
    vec3 n = normalize(texelFetch(u_gbuffer_normal, pixel, 0).xyz);
    vec3 v = normalize(u_eye - g.xyz);
    vec4 reflected = texelFetch(u_reflection, pixel, 0);
#if BACKGROUND_ENV
    vec3 r = reflect(-v, n);
    vec3 behind = textureLod(u_env, equirect_uv(u_env_from_world * r), 0.0).rgb;
#else
    vec3 behind = u_background;
#endif
    vec3 radiance = reflected.a > 0.5 ? reflected.rgb : behind;
#ifdef MATERIAL_SURFACE
    mat3 frame = mat3(1.0);  // a mirror has no normal map
    material_surface(texelFetch(u_gbuffer_uvs, pixel, 0), frame);
#endif
    f_color = vec4(mirror_reflectance(max(dot(n, v), 0.0)) * radiance, 1.0);
}
