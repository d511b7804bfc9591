// Provides the viewer's display: the HDR frame (an uploaded array's row 0 at the top, u_top_first; a rendered
// texture's at the bottom) × 2^exposure, the tone curve of reflets.imageio.tonemap (clamp, or Narkowicz's ACES fit
// first), the exact sRGB OETF; the 8-bit window rounds it as the PNG writer does.
uniform sampler2D u_image;
uniform float u_exposure;
uniform int u_aces;
uniform int u_top_first;

in vec2 v_uv;
out vec4 f_color;

vec3 srgb(vec3 x) {
    return mix(12.92 * x, 1.055 * pow(max(x, vec3(0.0031308)), vec3(1.0 / 2.4)) - 0.055, greaterThan(x, vec3(0.0031308)));
}

void main() {
    vec3 x = clamp(texture(u_image, vec2(v_uv.x, u_top_first == 1 ? 1.0 - v_uv.y : v_uv.y)).rgb * exp2(u_exposure), 0.0, 1e6);
    if (u_aces == 1) x = (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14);
    f_color = vec4(srgb(clamp(x, 0.0, 1.0)), 1.0);
}
