// Provides the shadow pass's fragment stage for a cut-out material (glTF alphaMode MASK): where its coverage — the
// base colour's alpha × its texture's (gltf.glsl's material_surface reads the same) — is under the cut-off, the
// surface casts no shadow.
in vec2 v_uv;
in vec2 v_uv1;
uniform vec4 m_base_color;
uniform float m_alpha_cutoff;
#if BRDF_GLTF_BASE_MAP
uniform sampler2D m_base_color_map;
uniform mat3 m_base_color_map_uv;
#endif

void main() {
    float coverage = m_base_color.a;
#if BRDF_GLTF_BASE_MAP
    vec2 uv = BRDF_GLTF_BASE_MAP == 2 ? v_uv1 : v_uv;  // the flag: 1 + the texture's uv set
    coverage *= texture(m_base_color_map, (m_base_color_map_uv * vec3(uv, 1.0)).xy).a;
#endif
    if (coverage < m_alpha_cutoff) discard;
}
