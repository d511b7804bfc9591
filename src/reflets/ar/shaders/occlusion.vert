// Provides the self-occlusion pass's vertex stage (004 §5.1, per vertex): vertex i is one point on texel i of the
// square accumulation texture (row-major from the bottom row) carrying its share (4/N) Σ_k max(0, n·ω_k)
// visible_k over one batch of directions, each an orthographic depth map tiled in one atlas. The sum is done
// here, not per fragment: vertices are shaded in full SIMD batches, a one-pixel point wastes most of a
// fragment quad (a 4 × 4 block on llvmpipe).
struct OcclusionView {
    vec4 affine[3];  // (p, 1) → texel x, y inside the view's tile and window depth
    vec4 direction;  // ω_k (towards the sky); w: world-to-depth scale of the view
};
// the batch's views (a uniform block: vertex-stage storage buffers are optional in OpenGL 4.3)
layout(std140, binding = 0) uniform OcclusionViews { OcclusionView views[OCCLUSION_BATCH]; };

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;  // unit (or zero: no light)

uniform int u_side;         // texels per side of the accumulation texture
uniform sampler2D u_depth;  // the atlas, raw depths (no comparison)
uniform int u_count;        // views in the batch
uniform int u_columns;      // tiles per atlas row
uniform int u_resolution;   // texels per tile side
uniform float u_weight;     // 4 / N
// world units: slope bias per unit tan θ, constant bias, offset along the normal; the largest tan θ used
uniform vec4 u_bias;

flat out float v_value;

void main() {
    vec4 p = vec4(in_position + u_bias.z * in_normal, 1.0);
    float sum = 0.0;
    for (int k = 0; k < u_count; ++k) {
        OcclusionView view = views[k];
        float c = dot(in_normal, view.direction.xyz);
        if (c <= 0.0) {
            continue;
        }
        vec2 local = vec2(dot(view.affine[0], p), dot(view.affine[1], p));
        ivec2 tile = ivec2(k % u_columns, k / u_columns) * u_resolution;
        ivec2 texel = clamp(ivec2(floor(local)), ivec2(0), ivec2(u_resolution - 1)) + tile;
        float tan_theta = min(sqrt(max(1.0 - c * c, 0.0)) / c, u_bias.w);
        float bias = (u_bias.x * tan_theta + u_bias.y) * view.direction.w;
        if (dot(view.affine[2], p) - bias <= texelFetch(u_depth, texel, 0).r) {
            sum += c;
        }
    }
    v_value = u_weight * sum;
    vec2 texel = vec2(gl_VertexID % u_side, gl_VertexID / u_side) + 0.5;
    gl_Position = vec4(texel * (2.0 / float(u_side)) - 1.0, 0.0, 1.0);
}
