// The model fragment shader of the demo renderer's G-buffer pass. It is the
// same with and without MSAA: the retrofit only changes which framebuffer
// is bound. Outputs (bound by name to the layout's attachment numbers):
//   o_color     base colour (texture x factor), a = 1, or 0 for an object that
//               opted out of anti-aliasing (the resolve's selective-AA flag)
//   o_position  view-space position, w = 1
//   o_normal    view-space unit normal, w = gloss = 1 - roughness (not normalised)
//   o_specular  F0 = mix(0.04, base, metallic), a = metallic
//   o_emissive  emitted radiance (linear HDR)
// The scene-adaptive plan compiles it without the outputs the scene does not
// need: GBUFFER_NO_SPECULAR (every material writes one specular value, which
// the lighting pass gets as a uniform) and GBUFFER_NO_EMISSIVE (no material
// emits).

in vec3 v_position;
in vec3 v_normal;
in vec2 v_uv;

uniform vec4 u_base_color;
uniform sampler2D u_base_texture;       // a white texel when the material has none
uniform float u_metallic;
uniform float u_roughness;
uniform vec3 u_emissive;
uniform sampler2D u_emissive_texture;   // a white texel when the material has none
uniform float u_alpha_cutoff;           // fragments with alpha below it are discarded (-1: opaque)
uniform int u_double_sided;
uniform float u_no_antialias;           // 1: the object takes one sample per pixel

out vec4 o_color;
out vec4 o_position;
out vec4 o_normal;
#ifndef GBUFFER_NO_SPECULAR
out vec4 o_specular;
#endif
#ifndef GBUFFER_NO_EMISSIVE
out vec4 o_emissive;
#endif

void main() {
    vec4 base = u_base_color * texture(u_base_texture, v_uv);
    if (base.a < u_alpha_cutoff) {
        discard;
    }
    float len = length(v_normal);
    vec3 n = len > 1e-8 ? v_normal / len : vec3(0.0, 0.0, 1.0);
    if (u_double_sided != 0 && !gl_FrontFacing) {
        n = -n;
    }
    o_color = vec4(base.rgb, 1.0 - u_no_antialias);
    o_position = vec4(v_position, 1.0);
    o_normal = vec4(n, 1.0 - clamp(u_roughness, 0.0, 1.0));
#ifndef GBUFFER_NO_SPECULAR
    float metallic = clamp(u_metallic, 0.0, 1.0);
    o_specular = vec4(mix(vec3(0.04), base.rgb, metallic), metallic);
#endif
#ifndef GBUFFER_NO_EMISSIVE
    o_emissive = vec4(u_emissive * texture(u_emissive_texture, v_uv).rgb, 1.0);
#endif
}
