// Passes the pixels whose value in u_value's red is above SELECT_ABOVE and
// discards the rest (src/second_layer.rs): with the first layer's outside
// flag (a sample lies outside its cluster: only those pixels can have a
// second cluster) it marks them in the second layer's stencil, for the
// second resolve to run behind an early stencil test on them alone; with
// the second layer's coverage, it counts the pixels that have a second
// layer under an occlusion query (src/lighting_check.rs).

uniform sampler2D u_value;

out vec4 o_unused;

void main() {
    if (texelFetch(u_value, ivec2(gl_FragCoord.xy), 0).r <= SELECT_ABOVE) discard;
    o_unused = vec4(0.0);
}
