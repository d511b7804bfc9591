// Provides the shadow pass's fragment stage for a cut-out material (glTF alphaMode MASK): where its coverage — the
// base colour's alpha × its texture's (gltf.glsl's material_surface reads the same) — is under the cut-off, the
// surface casts no shadow. A blended surface (alphaMode BLEND) casts a dithered one: a fragment of coverage a is
// kept on a of the texels of each 4 × 4 block (ordered dither), which the lookups' PCF averages into a shadow letting
// about 1 − a through.
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
#if BRDF_GLTF_BLEND
    const float bayer[16] = float[16](0.0, 8.0, 2.0, 10.0, 12.0, 4.0, 14.0, 6.0, 3.0, 11.0, 1.0, 9.0, 15.0, 7.0, 13.0, 5.0);
    ivec2 cell = ivec2(gl_FragCoord.xy) & 3;
    if (coverage <= (bayer[cell.y * 4 + cell.x] + 0.5) / 16.0) discard;
#else
    if (coverage < m_alpha_cutoff) discard;
#endif
}
