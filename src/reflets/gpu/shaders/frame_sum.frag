// Provides the frame sum's pass: each output pixel the sum of its u_side × u_side block of the drawn frame (the
// supersampled samples of one pixel), times u_scale (1 / side² when a frame is added, 1 / frames for the mean).
uniform sampler2D u_frame;
uniform int u_side;
uniform float u_scale;

out vec4 f_color;

void main() {
    ivec2 corner = ivec2(gl_FragCoord.xy) * u_side;
    vec4 sum = vec4(0.0);
    for (int j = 0; j < u_side; ++j)
        for (int i = 0; i < u_side; ++i)
            sum += texelFetch(u_frame, corner + ivec2(i, j), 0);
    f_color = vec4(sum.rgb * u_scale, 1.0);
}
