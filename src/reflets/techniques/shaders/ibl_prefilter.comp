// Provides the GGX prefiltering of an equirectangular environment (reflets/techniques/ibl.py): texel p of the
// level being written holds, for the direction R through it (N = V = R, the split sum's assumption),
// Σ L(l_k) (n·l_k) / Σ (n·l_k) over PREFILTER samples l_k of a GGX lobe of roughness u_alpha — each read at the
// source mip whose texel solid angle matches the sample's (filtered importance sampling, Křivánek & Colbert
// 2008), which keeps a few hundred samples free of fireflies. α = 0 copies the source (at the matching mip).
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba32f, binding = 0) writeonly uniform image2D u_out;
uniform sampler2D u_source;          // the environment with its mips, the map's own frame
uniform float u_alpha;
uniform int u_samples;
uniform ivec2 u_size;                // of the level written
uniform float u_source_texel_omega;  // 4π / (W H) of the source's level 0
uniform float u_copy_lod;            // α = 0: the source mip of the level's resolution

vec3 equirect_direction(vec2 uv) {
    float phi = TWO_PI * uv.x, theta = PI * uv.y;
    return vec3(sin(theta) * sin(phi), cos(theta), -sin(theta) * cos(phi));
}

float radical_inverse(uint bits) {
    bits = (bits << 16u) | (bits >> 16u);
    bits = ((bits & 0x55555555u) << 1u) | ((bits & 0xAAAAAAAAu) >> 1u);
    bits = ((bits & 0x33333333u) << 2u) | ((bits & 0xCCCCCCCCu) >> 2u);
    bits = ((bits & 0x0F0F0F0Fu) << 4u) | ((bits & 0xF0F0F0F0u) >> 4u);
    bits = ((bits & 0x00FF00FFu) << 8u) | ((bits & 0xFF00FF00u) >> 8u);
    return float(bits) * 2.3283064365386963e-10;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, u_size))) return;
    vec2 uv = (vec2(p) + 0.5) / vec2(u_size);
    if (u_alpha <= 0.0) {
        imageStore(u_out, p, vec4(textureLod(u_source, uv, u_copy_lod).rgb, 1.0));
        return;
    }
    vec3 n = equirect_direction(uv);
    vec3 up = abs(n.y) < 0.999 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0);
    vec3 t = normalize(cross(up, n));
    vec3 b = cross(n, t);
    float a2 = u_alpha * u_alpha;
    vec3 sum = vec3(0.0);
    float weight = 0.0;
    for (int i = 0; i < u_samples; ++i) {
        vec2 xi = vec2((float(i) + 0.5) / float(u_samples), radical_inverse(uint(i)));
        float cos_h = sqrt((1.0 - xi.x) / (1.0 + (a2 - 1.0) * xi.x));
        float sin_h = sqrt(max(0.0, 1.0 - cos_h * cos_h));
        float phi = TWO_PI * xi.y;
        vec3 h = t * (sin_h * cos(phi)) + b * (sin_h * sin(phi)) + n * cos_h;
        vec3 l = 2.0 * cos_h * h - n;
        float nl = dot(n, l);
        if (nl <= 0.0) continue;
        float q = cos_h * cos_h * (a2 - 1.0) + 1.0;
        float pdf = a2 / (PI * q * q) * 0.25;  // D(h) cos_h / (4 v·h) with v = n: v·h = cos_h
        float omega = 1.0 / (float(u_samples) * pdf);
        float lod = max(0.5 * log2(omega / u_source_texel_omega) + 1.0, 0.0);
        sum += textureLod(u_source, equirect_uv(l), lod).rgb * nl;
        weight += nl;
    }
    imageStore(u_out, p, vec4(sum / max(weight, 1e-8), 1.0));
}
