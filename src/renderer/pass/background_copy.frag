// Copies the single-sampled background into the G-buffer's emissive
// attachment. Bound to a multisampled framebuffer, the one fragment each
// pixel gets writes its value to every covered sample: the full-screen
// triangle covers them all, so every sample receives the background. That
// is the copy glBlitFramebuffer cannot make (it cannot write a multisampled
// target).

uniform sampler2D u_background;
out vec4 o_emissive;

void main() {
    o_emissive = texelFetch(u_background, ivec2(gl_FragCoord.xy), 0);
}
