// SMAA pass 3, neighbourhood blending. A pixel takes from the pixel above
// what its own weights say (.r), from the one to the left likewise (.b),
// and from the ones below and to the right what they say the pixel across
// their top (.g) and left (.a) edges takes. It blends along one axis only,
// the one where it takes most (a staircase's horizontal and vertical edges
// describe the same line twice), in linear light, so that the mix is the
// coverage the areas stand for; the image is sRGB-encoded.
// A pixel that takes nothing is copied exactly.

uniform sampler2D u_image;
uniform sampler2D u_weights;

out vec4 o_color;

vec3 to_linear(vec3 c) {
    return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), step(vec3(0.04045), c));
}

vec3 to_srgb(vec3 c) {
    c = clamp(c, 0.0, 1.0);
    return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}

void main() {
    ivec2 p = ivec2(gl_FragCoord.xy);
    ivec2 last = textureSize(u_image, 0) - 1;
    vec4 here = texelFetch(u_image, p, 0);
    vec4 own = texelFetch(u_weights, p, 0);
    float up = own.r;
    float left = own.b;
    float down = p.y > 0 ? texelFetch(u_weights, p - ivec2(0, 1), 0).g : 0.0;
    float right = p.x < last.x ? texelFetch(u_weights, p + ivec2(1, 0), 0).a : 0.0;
    if (max(max(up, down), max(left, right)) == 0.0) {
        o_color = here;
        return;
    }
    bool across_rows = max(up, down) >= max(left, right);
    vec2 take = across_rows ? vec2(up, down) : vec2(right, left);
    ivec2 step_to = across_rows ? ivec2(0, 1) : ivec2(1, 0);
    vec3 first = texelFetch(u_image, clamp(p + step_to, ivec2(0), last), 0).rgb;
    vec3 second = texelFetch(u_image, clamp(p - step_to, ivec2(0), last), 0).rgb;
    vec3 mixed = to_linear(here.rgb) * (1.0 - take.x - take.y)
               + to_linear(first) * take.x + to_linear(second) * take.y;
    o_color = vec4(to_srgb(mixed), here.a);
}
