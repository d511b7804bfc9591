// Provides the environment background: the map seen along each camera ray (constant colours are a clear).
in vec2 v_ndc;
uniform mat4 u_inv_view_proj;  // inverse of projection × view with the eye at the origin
uniform mat3 u_env_from_world;  // inverse of the environment's rotation
uniform sampler2D u_env;
out vec4 f_color;
void main() {
    vec4 p = u_inv_view_proj * vec4(v_ndc, 1.0, 1.0);  // the near-plane point, the eye at the origin
    vec3 d = normalize(p.xyz / p.w);
    f_color = vec4(textureLod(u_env, equirect_uv(u_env_from_world * d), 0.0).rgb, 1.0);
}
