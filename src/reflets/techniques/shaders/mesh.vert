// Provides the world-space vertex stage shared by mesh passes (meshes are stored in world space).
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec4 in_tangent;
layout(location = 3) in vec2 in_uv;
layout(location = 4) in vec2 in_uv1;  // the second uv set (glTF's TEXCOORD_1; the first again when none)

uniform mat4 u_view_proj;

out vec3 v_position;
out vec3 v_normal;
out vec4 v_tangent;
out vec2 v_uv;
out vec2 v_uv1;
invariant gl_Position;  // the depth pre-pass and the shading pass must rasterise the same depths

void main() {
    v_position = in_position;
    v_normal = in_normal;
    v_tangent = in_tangent;
    v_uv = in_uv;
    v_uv1 = in_uv1;
    gl_Position = u_view_proj * vec4(in_position, 1.0);
}
