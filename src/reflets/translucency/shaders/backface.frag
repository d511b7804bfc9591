// Provides the back-face pass of the translucency technique's image-space refraction (Wyman 2005): for each
// pixel, the nearest surface of a translucent mesh whose outward normal faces away from the camera — where a
// ray refracted into the object leaves it. World position (w = 1: a surface) and the outward normal.
in vec3 v_position;
in vec3 v_normal;
in vec4 v_tangent;
in vec2 v_uv;

uniform vec3 u_eye;

layout(location = 0) out vec4 f_position;
layout(location = 1) out vec4 f_normal;

void main() {
    vec3 n = normalize(v_normal);  // outward (closed meshes); the winding is not relied on
    if (dot(n, u_eye - v_position) > 0.0) discard;  // a front face
    f_position = vec4(v_position, 1.0);
    f_normal = vec4(n, 0.0);
}
