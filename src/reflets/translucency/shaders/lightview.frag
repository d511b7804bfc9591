// Provides the light-view pass of the translucency technique: the world position (w = 1: a surface) and the
// normal facing the light of the first surface along each light ray (the document's distance and normal maps).
in vec3 v_position;
in vec3 v_normal;
in vec4 v_tangent;
in vec2 v_uv;

layout(location = 0) out vec4 f_position;
layout(location = 1) out vec4 f_normal;

void main() {
    vec3 n = normalize(v_normal);
    f_position = vec4(v_position, 1.0);
    f_normal = vec4(gl_FrontFacing ? n : -n, 0.0);
}
