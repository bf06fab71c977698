// Marks, in the second layer's stencil, the pixels the first layer's resolve
// took its slow path on (its complex flag): only those can have a second
// cluster, and the second layer's resolve runs behind an early stencil test
// on them alone (src/second_layer.rs).

uniform sampler2D u_complex;

out vec4 o_unused;

void main() {
    if (texelFetch(u_complex, ivec2(gl_FragCoord.xy), 0).r < 0.5) discard;
    o_unused = vec4(0.0);
}
