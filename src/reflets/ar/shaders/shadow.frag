// The document's sphere shadows on the ground, one texel of the shadow texture per fragment: the light fraction
// Π_i (1 − a_i) left by the spheres, a_i = sin²(angular radius) · cos(elevation) · min(L_i / A, π) with L_i the
// captured map's radiance toward the sphere at the mip level of its solid angle (the NumPy twin:
// reflets.ar.document.shadow_texture_numpy).
layout(std430, binding = 0) readonly buffer Spheres { vec4 spheres[]; };  // centre, radius

uniform samplerCube u_environment;
uniform vec2 u_origin;    // (x, z) of texel centre 0
uniform float u_spacing;  // between texel centres
uniform int u_count;
uniform float u_size;     // the map's face size (texels)
uniform float u_ambient;  // A: the ground's unoccluded irradiance over π (its RGB norm)

out vec4 frag_color;

void main() {
    ivec2 texel = ivec2(gl_FragCoord.xy);  // x along the columns, z along the rows
    vec3 p = vec3(u_origin.x + u_spacing * float(texel.x), 0.0, u_origin.y + u_spacing * float(texel.y));
    float remaining = 1.0;
    for (int i = 0; i < u_count; ++i) {
        vec3 d = spheres[i].xyz - p;
        float distance = length(d);
        vec3 direction = d / distance;
        float radius = spheres[i].w;
        float s = clamp(radius / distance, 0.0, 1.0);
        float cos_w = clamp(direction.y, 0.0, 1.0);
        float level = log2(max(u_size * radius / distance, 1e-6));
        float local = length(textureLod(u_environment, direction, level).rgb);
        remaining *= 1.0 - clamp(s * s * cos_w * min(local / u_ambient, PI), 0.0, 1.0);
    }
    frag_color = vec4(remaining, 0.0, 0.0, 1.0);
}
