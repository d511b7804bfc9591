// Provides the reflectors' G-buffer: world position + reflector id (0: not a reflector), the shading normal
// facing the camera and both uv sets (a mirror's maps), of the nearest surface at each pixel (every mesh and
// emitter is drawn: they hide reflectors).
in vec3 v_position;
in vec3 v_normal;
in vec4 v_tangent;
in vec2 v_uv;
in vec2 v_uv1;

uniform float u_reflector_id;

layout(location = 0) out vec4 f_position;
layout(location = 1) out vec4 f_normal;
layout(location = 2) out vec4 f_uvs;

void main() {
    vec3 n = normalize(v_normal);
    if (!gl_FrontFacing) n = -n;
    f_position = vec4(v_position, u_reflector_id);
    f_normal = vec4(n, 0.0);
    f_uvs = vec4(v_uv, v_uv1);
}
