// Provides an image copy drawn on the GPU: colour and depth of one image into a framebuffer of the same size (a
// depth blit is a CPU copy on llvmpipe, which first waits for everything drawn before it).
uniform sampler2D u_colour;
uniform sampler2D u_depth;  // compare mode off: the stored value

out vec4 f_color;

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    f_color = texelFetch(u_colour, pixel, 0);
    gl_FragDepth = texelFetch(u_depth, pixel, 0).r;
}
