// Provides the reflected vertex stage of the fermat method (passes 3 of the document, §3.2): each scene vertex V
// is moved to its reflection point P on the reflector (in_mirror: solve.vert's result for this eye, the solver of
// the SOLVER flag), so the rasteriser draws the mirror image; depth is |PV| (the nearest reflected object wins,
// visibility level 1).

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec4 in_tangent;
layout(location = 3) in vec2 in_uv;
layout(location = 4) in vec2 in_uv1;
layout(location = 5) in vec4 in_mirror;  // P, and 1 where the solver converged

uniform mat4 u_view_proj;
uniform float u_depth_range;  // |PV| mapped to [0, 1] over [0, u_depth_range]

out vec3 v_position;
out vec3 v_normal;
out vec4 v_tangent;
out vec2 v_uv;
out vec2 v_uv1;
out vec3 v_mirror_point;
out float v_valid;

void main() {
    vec3 mirror_point = in_mirror.xyz;
    v_position = in_position;
    v_normal = in_normal;
    v_tangent = in_tangent;
    v_uv = in_uv;
    v_uv1 = in_uv1;
    v_mirror_point = mirror_point;
    // converged is enough here: where P faces away from E (or V lies behind the mirror) the fragment tests of
    // reflected.frag remove the part of the triangle that is not seen, so the rest of it is not lost
    v_valid = in_mirror.w;
    vec4 clip = u_view_proj * vec4(mirror_point, 1.0);
    clip.z = (2.0 * clamp(length(in_position - mirror_point) / u_depth_range, 0.0, 1.0) - 1.0) * clip.w;
    gl_Position = clip;
}
