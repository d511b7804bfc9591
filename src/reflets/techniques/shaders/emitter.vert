// Provides the vertex stage for drawing area-light polygons as visible emitters (uv: the quad's (u, v) for masks).
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec2 in_uv;
uniform mat4 u_view_proj;
out vec2 v_uv;
void main() {
    v_uv = in_uv;
    gl_Position = u_view_proj * vec4(in_position, 1.0);
}
