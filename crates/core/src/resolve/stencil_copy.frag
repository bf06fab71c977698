// Writes the host's stencil from its multisampled twin: each pixel takes
// the stencil value of the sample the resolve chose as its reference
// (src/resolve/stencil.rs).
//
// Defines set by src/resolve/stencil.rs:
//   STENCIL_EXPORT   write the value with GL_ARB_shader_stencil_export (the
//                    preamble enables it); otherwise one pass per bit:
//                    fragments whose value has bit u_bit clear are discarded,
//                    the others write it

// The twin's depth-stencil texture, read as GL_STENCIL_INDEX.
uniform usampler2DMS u_stencil;
// The resolve's reference sample per pixel.
uniform usampler2D u_reference;
#ifndef STENCIL_EXPORT
uniform uint u_bit;
#endif

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    int r = int(texelFetch(u_reference, p, 0).r);
    uint value = texelFetch(u_stencil, p, r).r;
#ifdef STENCIL_EXPORT
    gl_FragStencilRefARB = int(value);
#else
    if ((value & u_bit) == 0u) discard;
#endif
}
