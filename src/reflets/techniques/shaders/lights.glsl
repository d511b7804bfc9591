// Provides direct_lighting(x, frame, wo): point, directional, sampled area and environment lights.
// Light data arrive in std430 buffers filled by reflets/techniques/forward.py (layouts documented there).
layout(std430, binding = 0) readonly buffer PointLights { vec4 point_data[]; };   // (position, cone scale), (intensity, shadow view + 1), (cone axis, cone offset)
const int POINT_STRIDE = 3;

// A point light's cone (glTF spot light, KHR_lights_punctual's smooth falloff): t^2, t = clamp(cos * scale + offset)
// along the direction from the light; 1 for an isotropic light (scale 0, offset 1).
float point_cone(int i, vec3 from_light) {
    float t = clamp(dot(point_data[POINT_STRIDE * i + 2].xyz, from_light) * point_data[POINT_STRIDE * i].w
                    + point_data[POINT_STRIDE * i + 2].w, 0.0, 1.0);
    return t * t;
}
layout(std430, binding = 1) readonly buffer DirLights { vec4 dir_data[]; };       // (to-light dir, shadow cascades), (irradiance, first shadow view + 1)
layout(std430, binding = 2) readonly buffer AreaSamples { vec4 area_data[]; };    // (y, dA), (n_L, two_sided), (L, 0)
#if N_AREA > 0
uniform vec4 u_area_runs[N_AREA_LIGHTS];  // per area light: its first sample, sample count, soft-shadow code
#endif
layout(std430, binding = 3) readonly buffer EnvSamples { vec4 env_data[]; };      // direction, L * solid angle

#include "reflets/techniques/shaders/shadows.glsl"

// ENV_IBL: the environment by the split sum (reflets/techniques/ibl.py) instead of the N_ENV grid.
#if ENV_IBL
uniform sampler2D u_ibl_radiance;       // GGX-prefiltered radiance; mip k: α = (k / (IBL_LEVELS − 1))²
uniform sampler2D u_ibl_irradiance;     // ∫ L max(0, n·ω) dω per normal
uniform mat3 u_ibl_env_from_world;
uniform vec3 u_ibl_albedo[IBL_NODES];  // the material's specular directional albedo at μ = (k + ½) / IBL_NODES
uniform vec3 u_ibl_diffuse;            // its Lambertian albedo
uniform float u_ibl_alpha;             // its main lobe's GGX-equivalent roughness
uniform vec3 u_ibl_untinted[IBL_NODES];  // the part of u_ibl_albedo a material's colour maps leave as it is

vec3 image_based_lighting(vec3 x, mat3 frame, vec3 wo) {
    vec3 n = frame[2], v = frame * wo;
#ifdef MATERIAL_IBL
    // a material whose parameters vary over the surface (textures) gives its albedos per fragment
    vec3 diffuse_albedo, albedo;
    float alpha;
    material_ibl(dot(n, v), diffuse_albedo, albedo, alpha);
#else
    vec3 diffuse_albedo = u_ibl_diffuse;
    float alpha = u_ibl_alpha;
    int k0, k1;
    float fk;
    ibl_nodes(dot(n, v), k0, k1, fk);
    vec3 albedo = mix(u_ibl_albedo[k0], u_ibl_albedo[k1], fk);
#ifdef MATERIAL_IBL_SCALE
    // mapped colours (reflets/brdf/maps.py), a translucent albedo map: the albedos × texels (mixed from the curves at
    // 0 for an affine colour), except the share of an interface the map does not tint (a translucent material's
    // reflection: u_ibl_untinted)
    vec3 untinted = mix(u_ibl_untinted[k0], u_ibl_untinted[k1], fk);
    material_ibl_scale(dot(n, v), untinted, diffuse_albedo, albedo);
#endif
#endif
    vec3 diffuse = diffuse_albedo * INV_PI * texture(u_ibl_irradiance, equirect_uv(u_ibl_env_from_world * n)).rgb;
    // the lobe's dominant direction, between r and n as roughness grows (Lagarde & de Rousiers 2014): the
    // prefiltered lobe is centred on r (n = v = r), a rough BRDF lobe leans towards the normal
    float smooth_ = 1.0 - alpha;
    vec3 r = normalize(mix(n, reflect(-v, n), smooth_ * (sqrt(smooth_) + alpha)));
    vec3 seen_diffuse = vec3(1.0), seen_specular = vec3(1.0);
#if ENV_VIEWS > 0 && SHADOW_VIEWS > 0
    environment_visibility(x, n, r, alpha, seen_diffuse, seen_specular);  // the scene's occlusion
#endif
    float level = sqrt(alpha) * float(IBL_LEVELS - 1);
    vec3 prefiltered = textureLod(u_ibl_radiance, equirect_uv(u_ibl_env_from_world * r), level).rgb;
    vec3 light = seen_diffuse * diffuse + seen_specular * albedo * prefiltered;
#ifdef MATERIAL_COAT
    // a clear coat (glTF): its own prefiltered lookup about its own normal, over the base by its Fresnel weight
    float coat_weight, coat_alpha, coat_albedo;
    vec3 coat_n;
    material_coat_ibl(frame, v, coat_weight, coat_n, coat_alpha, coat_albedo);
    vec3 coat_dir = u_ibl_env_from_world * reflect(-v, coat_n);
    vec3 coat_light = textureLod(u_ibl_radiance, equirect_uv(coat_dir), sqrt(coat_alpha) * float(IBL_LEVELS - 1)).rgb;
    light = (1.0 - coat_weight) * light + coat_weight * seen_specular * coat_albedo * coat_light;
#endif
#ifdef MATERIAL_SURFACE
    light *= material_occlusion();  // the material's own ambient occlusion (glTF: the environment's light only)
#endif
    return light;
}
#endif

// Light counts N_POINT, N_DIR, N_AREA, N_ENV are compile-time flags, and a light type the scene lacks gets no
// code at all: on llvmpipe a loop whose trip count is a constant 0 still costs nearly a light's shading
// (measured: three such loops next to one GGX point light tripled its frame time).

// Outgoing radiance from all lights at x; `frame` maps local (t, b, n) to world, wo is local.
vec3 direct_lighting(vec3 x, mat3 frame, vec3 wo) {
    mat3 to_local = transpose(frame);
    vec3 n = frame[2];
    vec3 sum = vec3(0.0);
#if N_POINT > 0
    for (int i = 0; i < N_POINT; ++i) {
        vec3 d = point_data[POINT_STRIDE * i].xyz - x;
        float r2 = dot(d, d);
        vec3 wi = d * inversesqrt(r2);
        float cos_x = dot(n, wi);
        float cone = point_cone(i, -wi);
        if (cos_x <= 0.0 || cone <= 0.0) continue;
        float v = point_visibility(i, x, n);
        if (v <= 0.0) continue;
        sum += brdf_eval(wo, to_local * wi) * point_data[POINT_STRIDE * i + 1].rgb * (cone * v * cos_x / r2);
    }
#endif
#if N_DIR > 0
    for (int i = 0; i < N_DIR; ++i) {
        vec3 wi = dir_data[2 * i].xyz;
        float cos_x = dot(n, wi);
        if (cos_x <= 0.0) continue;
        float v = dir_visibility(i, x, n);
        if (v <= 0.0) continue;
        sum += brdf_eval(wo, to_local * wi) * dir_data[2 * i + 1].rgb * (v * cos_x);
    }
#endif
    // Area lights as weighted midpoint samples (eq 2.8 of the area-light document): f L cosθx cosθy / r² dA.
    // Shadows: each light's soft-shadow ratio (shadows.glsl), once per light: a branch inside the sample loop
    // would run for every sample on llvmpipe.
#if N_AREA > 0
    for (int l = 0; l < N_AREA_LIGHTS; ++l) {
    float shadow = soft_visibility(u_area_runs[l].z, x, frame, wo);
    int first = int(u_area_runs[l].x + 0.5), end = first + int(u_area_runs[l].y + 0.5);
    for (int i = first; i < end; ++i) {
        vec4 p = area_data[3 * i];
        vec4 nl = area_data[3 * i + 1];
        vec3 d = p.xyz - x;
        float r2 = dot(d, d);
        vec3 wi = d * inversesqrt(r2);
        float cos_x = dot(n, wi);
        float cos_y = -dot(nl.xyz, wi);
        if (nl.w > 0.5) cos_y = abs(cos_y);
        if (cos_x <= 0.0 || cos_y <= 0.0) continue;
#ifdef MATERIAL_PATCH_EVAL
        vec3 f = brdf_eval_patch(wo, to_local * wi, sqrt(p.w * cos_y / (PI * r2)));  // the sample's patch
#else
        vec3 f = brdf_eval(wo, to_local * wi);
#endif
        sum += f * area_data[3 * i + 2].rgb * (shadow * cos_x * cos_y * p.w / r2);
    }
    }
#endif
#if N_ENV > 0
    for (int i = 0; i < N_ENV; ++i) {
        vec3 wi = env_data[2 * i].xyz;
        float cos_x = dot(n, wi);
        if (cos_x <= 0.0) continue;
        sum += brdf_eval(wo, to_local * wi) * env_data[2 * i + 1].rgb * cos_x;
    }
#endif
#if ENV_IBL
    sum += image_based_lighting(x, frame, wo);
#endif
    return sum;
}
