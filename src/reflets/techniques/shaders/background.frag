// Provides the environment background: the map seen along each camera ray (constant colours are a clear).
in vec2 v_ndc;
uniform mat4 u_inv_view_proj;
uniform mat3 u_env_from_world;  // inverse of the environment's rotation
uniform sampler2D u_env;
out vec4 f_color;
void main() {
    // reversed-Z: depth 1 is the near plane, 0 the far one (w = 0 there with an infinite far plane)
    vec4 a = u_inv_view_proj * vec4(v_ndc, 1.0, 1.0);
    vec4 b = u_inv_view_proj * vec4(v_ndc, 0.0, 1.0);
    vec3 d = normalize(b.xyz * a.w - a.xyz * b.w);  // b / b.w - a / a.w, times a.w b.w: no division by 0
    f_color = vec4(textureLod(u_env, equirect_uv(u_env_from_world * d), 0.0).rgb, 1.0);
}
