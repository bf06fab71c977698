// The second layer's stencil mask (method option `layers=2`): marks the
// pixels whose second resolved layer covers any of them (coverage above 0),
// so that the second lighting runs only there; colour is not written.

uniform sampler2D u_coverage;

out vec4 o_color;

void main() {
    if (texelFetch(u_coverage, ivec2(gl_FragCoord.xy), 0).r <= 0.0) discard;
    o_color = vec4(0.0);
}
