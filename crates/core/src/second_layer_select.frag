// Marks, in the second layer's stencil, the pixels a sample of which the
// first layer's resolve left out of its cluster (its outside flag): only
// those can have a second cluster, and the second layer's resolve runs
// behind an early stencil test on them alone (src/second_layer.rs).

uniform sampler2D u_outside;

out vec4 o_unused;

void main() {
    if (texelFetch(u_outside, ivec2(gl_FragCoord.xy), 0).r < 0.5) discard;
    o_unused = vec4(0.0);
}
