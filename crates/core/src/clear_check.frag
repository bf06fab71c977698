// Counts the pixels whose multisampled depth still holds the value
// begin_frame cleared it to (src/clear_check.rs): such a pixel was neither
// cleared nor drawn since. Sample 0 alone: a cleared pixel holds the
// host's clear value or geometry in every sample. Every u_step-th pixel
// in x and y: the fragment at (x, y) of a viewport u_step times smaller
// reads pixel (x, y) * u_step. Fragments of other pixels are discarded;
// an occlusion query counts the rest.

uniform sampler2DMS u_depth;
uniform float u_sentinel;
// Half a step of the depth format: the sentinel as stored reads back
// within it.
uniform float u_tolerance;
uniform int u_step;

void main() {
    float depth = texelFetch(u_depth, ivec2(gl_FragCoord.xy) * u_step, 0).r;
    if (abs(depth - u_sentinel) > u_tolerance) discard;
}
