// The depth pre-pass of method `sparse`: every opaque and alpha-tested
// object into the multisampled depth buffer only. It repeats exactly the
// alpha test of geometry.frag (same factor, texture and cutoff), so the
// depth holds the fragments the G-buffer pass keeps and no others; a
// fragment geometry.frag would discard must not hide the one behind it.

in vec2 v_uv;

uniform vec4 u_base_color;
uniform sampler2D u_base_texture;   // a white texel when the material has none
uniform float u_alpha_cutoff;       // -1: opaque

void main() {
    vec4 base = u_base_color * texture(u_base_texture, v_uv);
    if (base.a < u_alpha_cutoff) {
        discard;
    }
}
