// Forward shading of alpha-blended objects, drawn single-sampled into the
// HDR target after lighting, depth-tested against the resolved depth.
// Compiled after lighting.frag (with LIGHTING_FUNCTIONS_ONLY), whose lights
// and BRDF it uses. Inputs come from geometry.vert.

in vec3 v_position;
in vec3 v_normal;
in vec2 v_uv;

uniform vec4 u_base_color;
uniform sampler2D u_base_texture;       // a white texel when the material has none
uniform float u_metallic;
uniform float u_roughness;
uniform vec3 u_emissive;
uniform sampler2D u_emissive_texture;   // a white texel when the material has none

out vec4 o_color;

void main() {
    vec4 base = u_base_color * texture(u_base_texture, v_uv);
    float len = length(v_normal);
    vec3 n = len > 1e-8 ? v_normal / len : vec3(0.0, 0.0, 1.0);
    if (!gl_FrontFacing) {
        n = -n;   // only double-sided materials draw back faces
    }
    float p_len = length(v_position);
    vec3 v = p_len > 0.0 ? -v_position / p_len : vec3(0.0, 0.0, 1.0);
    float metallic = clamp(u_metallic, 0.0, 1.0);
    vec3 f0 = mix(vec3(0.04), base.rgb, metallic);
    float gloss = 1.0 - clamp(u_roughness, 0.0, 1.0);
    vec3 radiance = direct_light(v_position, n, v, base.rgb, metallic, f0, gloss);
    if (u_first_batch != 0) {
        radiance += u_emissive * texture(u_emissive_texture, v_uv).rgb + ambient_light(base.rgb, metallic, f0);
    }
    o_color = vec4(radiance, clamp(base.a, 0.0, 1.0));
}
