// Writes the second layer's depth (a colour output of its resolve) into the
// host's depth attachment for the second lighting (src/second_layer.rs);
// colour and stencil are not written.

uniform sampler2D u_layer_depth;

void main() {
    gl_FragDepth = texelFetch(u_layer_depth, ivec2(gl_FragCoord.xy), 0).r;
}
