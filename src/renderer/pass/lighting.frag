// Per-pixel deferred lighting of the demo renderer. It reads the resolved
// single-sample G-buffer and writes linear HDR radiance. Its source and
// defines are the same with and without MSAA: the retrofit hands it an
// ordinary G-buffer either way.
//
// The first part (lights, the BRDF, and the shading of one G-buffer texel
// or sample) is shared with the forward transparent pass and the per-sample
// lighting pass, which compile this file with LIGHTING_FUNCTIONS_ONLY
// defined, followed by transparent.frag or lighting_per_sample.frag.
//
// Lights come in batches of at most MAX_LIGHTS; the first batch also adds
// emission and the ambient term, later batches are added on top. With
// LIGHT_BLOCK defined (the per-sample pass) the light arrays live in the
// uniform block LightBlock (std140) instead, so that MAX_LIGHTS can be large
// enough for one draw to light a sample with every light.
//
// Material model (metallic-roughness, fed by the G-buffer):
//   base colour = color.rgb, F0 = specular.rgb, metallic = specular.a,
//   roughness = 1 - normal.w (gloss); GGX distribution, separable
//   Schlick-GGX visibility, Schlick Fresnel, Lambert diffuse.

#define PI 3.14159265358979

#define LIGHT_POINT 0
#define LIGHT_SPOT 1
#define LIGHT_DIRECTIONAL 2

uniform int u_light_count;
#ifdef LIGHT_BLOCK
layout(std140) uniform LightBlock {
    vec4 u_light_position[MAX_LIGHTS];
    vec4 u_light_direction[MAX_LIGHTS];
    vec4 u_light_color[MAX_LIGHTS];
    vec4 u_light_cone[MAX_LIGHTS];
};
#else
uniform vec4 u_light_position[MAX_LIGHTS];   // view-space position, range (0: unlimited)
uniform vec4 u_light_direction[MAX_LIGHTS];  // view-space unit direction of travel, kind
uniform vec4 u_light_color[MAX_LIGHTS];      // linear colour x intensity
uniform vec4 u_light_cone[MAX_LIGHTS];       // spot: cos(outer cone), cos(inner cone)
#endif
uniform vec3 u_ambient;                      // constant ambient radiance
uniform int u_first_batch;                   // 1: add emission and ambient

// The irradiance factor of light i at view-space point p, and the unit
// vector from p towards the light.
float light_falloff(int i, vec3 p, out vec3 to_light) {
    int kind = int(u_light_direction[i].w + 0.5);
    vec3 dir = u_light_direction[i].xyz;
    if (kind == LIGHT_DIRECTIONAL) {
        to_light = -dir;
        return 1.0;
    }
    vec3 offset = u_light_position[i].xyz - p;
    float dist2 = max(dot(offset, offset), 1e-8);
    float dist = sqrt(dist2);
    to_light = offset / dist;
    float falloff = 1.0 / dist2;
    float range = u_light_position[i].w;
    if (range > 0.0) {
        // Smooth window reaching zero at the range.
        float r = dist / range;
        float window = clamp(1.0 - r * r * r * r, 0.0, 1.0);
        falloff *= window * window;
    }
    if (kind == LIGHT_SPOT) {
        float cos_outer = u_light_cone[i].x;
        float cos_inner = u_light_cone[i].y;
        float t = clamp((dot(-to_light, dir) - cos_outer) / max(cos_inner - cos_outer, 1e-4), 0.0, 1.0);
        falloff *= t * t;
    }
    return falloff;
}

// Outgoing radiance towards v from the current batch of lights.
vec3 direct_light(vec3 p, vec3 n, vec3 v, vec3 base, float metallic, vec3 f0, float gloss) {
    float roughness = clamp(1.0 - gloss, 0.03, 1.0);
    float alpha = roughness * roughness;
    float alpha2 = alpha * alpha;
    float k = alpha * 0.5;
    float n_dot_v = clamp(dot(n, v), 1e-4, 1.0);
    float vis_v = n_dot_v / (n_dot_v * (1.0 - k) + k);
    vec3 diffuse_colour = base * (1.0 - metallic) / PI;
    vec3 sum = vec3(0.0);
    for (int i = 0; i < u_light_count; ++i) {
        vec3 l;
        float falloff = light_falloff(i, p, l);
        float n_dot_l = dot(n, l);
        if (n_dot_l <= 0.0 || falloff <= 0.0) {
            continue;
        }
        vec3 h = normalize(l + v);
        float n_dot_h = max(dot(n, h), 0.0);
        float v_dot_h = max(dot(v, h), 0.0);
        float denom = n_dot_h * n_dot_h * (alpha2 - 1.0) + 1.0;
        float distribution = alpha2 / (PI * denom * denom);
        float vis_l = n_dot_l / (n_dot_l * (1.0 - k) + k);
        float visibility = vis_l * vis_v / (4.0 * n_dot_l * n_dot_v);
        vec3 fresnel = f0 + (1.0 - f0) * pow(1.0 - v_dot_h, 5.0);
        vec3 brdf = (1.0 - fresnel) * diffuse_colour + fresnel * (distribution * visibility);
        sum += brdf * u_light_color[i].rgb * (falloff * n_dot_l);
    }
    return sum;
}

vec3 ambient_light(vec3 base, float metallic, vec3 f0) {
    return u_ambient * (base * (1.0 - metallic) + f0);
}

// The radiance of a background texel or sample (depth = clear depth): only
// what the background copy left in the emissive attachment, in the first batch.
vec3 shade_background(vec3 emissive) {
    return u_first_batch != 0 ? emissive : vec3(0.0);
}

// The radiance of one opaque G-buffer texel or sample towards the camera:
// the current batch of lights, plus emission and ambient light in the first
// batch. The inputs are the G-buffer's attachments as geometry.frag writes them.
vec3 shade_surface(vec3 base, vec3 p, vec4 normal_gloss, vec4 specular, vec3 emissive) {
    float len = length(normal_gloss.xyz);
    vec3 n = len > 1e-6 ? normal_gloss.xyz / len : vec3(0.0, 0.0, 1.0);
    float p_len = length(p);
    vec3 v = p_len > 0.0 ? -p / p_len : vec3(0.0, 0.0, 1.0);
    float metallic = clamp(specular.a, 0.0, 1.0);
    vec3 radiance = direct_light(p, n, v, base, metallic, specular.rgb, normal_gloss.w);
    if (u_first_batch != 0) {
        radiance += emissive + ambient_light(base, metallic, specular.rgb);
    }
    return radiance;
}

#ifndef LIGHTING_FUNCTIONS_ONLY

uniform sampler2D u_color;
uniform sampler2D u_position;
uniform sampler2D u_normal;
#ifdef GBUFFER_NO_SPECULAR
uniform vec4 u_specular_constant;   // the one value every material writes
#else
uniform sampler2D u_specular;
#endif
#ifdef GBUFFER_NO_EMISSIVE
uniform sampler2D u_background;     // no material emits: the background's own texture
#else
uniform sampler2D u_emissive;
#endif
uniform sampler2D u_depth;
uniform float u_clear_depth;

out vec4 o_color;

// The attachments a scene-adaptive G-buffer may leave out
// (GBUFFER_NO_SPECULAR, GBUFFER_NO_EMISSIVE), read as if they were there.
vec4 gbuffer_specular(ivec2 pixel) {
#ifdef GBUFFER_NO_SPECULAR
    return u_specular_constant;
#else
    return texelFetch(u_specular, pixel, 0);
#endif
}

vec3 gbuffer_emissive(ivec2 pixel, bool background) {
#ifdef GBUFFER_NO_EMISSIVE
    // The emissive attachment would hold the background copy there, else zero.
    return background ? texelFetch(u_background, pixel, 0).rgb : vec3(0.0);
#else
    return texelFetch(u_emissive, pixel, 0).rgb;
#endif
}

void main() {
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    if (texelFetch(u_depth, pixel, 0).r == u_clear_depth) {
        o_color = vec4(shade_background(gbuffer_emissive(pixel, true)), 1.0);
        return;
    }
    vec3 radiance = shade_surface(
        texelFetch(u_color, pixel, 0).rgb,
        texelFetch(u_position, pixel, 0).xyz,
        texelFetch(u_normal, pixel, 0),
        gbuffer_specular(pixel),
        gbuffer_emissive(pixel, false));
    o_color = vec4(radiance, 1.0);
}

#endif
