// The G-buffer pass of method `complex`: the model shader geometry.frag,
// unchanged, with its main() renamed to model_main() by a #define in front
// of it, then this main(), which runs it and also records whether the
// fragment covered only part of its pixel. Compiled with GL_ARB_gpu_shader5
// (or GL_ARB_sample_shading) for gl_SampleMaskIn.
//
// o_coverage goes to an extra R8 multisampled attachment that the clear set
// to 0: every sample keeps the flag of the fragment that last wrote it, so a
// pixel has a sample flagged 1 exactly when one of its surviving fragments
// had partial coverage (a triangle edge crosses the pixel).

uniform int u_full_mask;        // (1 << samples) - 1

out vec4 o_coverage;

void main() {
    model_main();
    o_coverage = vec4(gl_SampleMaskIn[0] == u_full_mask ? 0.0 : 1.0);
}
