// The document's object shading (004 §4.2, §4.4), vertex stage: world position and normal, and the diffuse
// radiance computed per vertex on the CPU (k_d P_V Σ_F L̄_F W_F(n) / π, Gouraud-interpolated as its code does).
in vec3 in_position;
in vec3 in_normal;
in vec3 in_diffuse;

uniform mat4 u_view_proj;

out vec3 v_position;
out vec3 v_normal;
out vec3 v_diffuse;

void main() {
    v_position = in_position;
    v_normal = in_normal;
    v_diffuse = in_diffuse;
    gl_Position = u_view_proj * vec4(in_position, 1.0);
}
