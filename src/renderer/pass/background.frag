// The scene background, drawn single-sampled into its own RGBA16F texture
// (linear HDR RGB). The renderer copies it into the G-buffer's emissive
// attachment afterwards (background_copy.frag).
//
// u_kind: 0 black, 1 vertical gradient, 2 star field.

in vec2 v_uv;
out vec4 o_color;

uniform int u_kind;
uniform vec3 u_zenith;          // gradient: colour straight up
uniform vec3 u_horizon;         // gradient: colour at and below the horizon
uniform uint u_seed;            // star field seed
uniform float u_star_cells;     // star grid cells per unit of direction (about one per 1.5 pixels)
uniform vec2 u_tan_half_fov;    // (tan(fov_x / 2), tan(fov_y / 2))
uniform mat4 u_view_to_world;   // rotation part of the inverse view matrix

// A small integer hash: multiply by odd constants, fold the high bits down.
uint hash3(uvec3 c, uint seed) {
    uint h = seed * 0x9E3779B1u + 0x632BE5ABu;
    h = (h ^ c.x) * 0xA3B1C56Bu;
    h ^= h >> 15;
    h = (h ^ c.y) * 0x6C8E9CF5u;
    h ^= h >> 13;
    h = (h ^ c.z) * 0xA3B1C56Bu;
    h ^= h >> 16;
    return h;
}

float unit_float(uint h) {
    return float(h >> 8) / 16777216.0;
}

vec3 world_direction() {
    vec2 ndc = v_uv * 2.0 - 1.0;
    vec3 view_dir = normalize(vec3(ndc * u_tan_half_fov, -1.0));
    return normalize(mat3(u_view_to_world) * view_dir);
}

vec3 star_field(vec3 dir) {
    vec3 p = dir * u_star_cells;
    vec3 cell = floor(p);
    uvec3 key = uvec3(ivec3(cell));
    uint h = hash3(key, u_seed);
    if (unit_float(h) > 0.02) {
        return vec3(0.0);
    }
    uint h2 = hash3(key, u_seed ^ 0x1F123BB5u);
    float brightness = mix(0.4, 6.0, pow(unit_float(h2), 4.0));
    float tint = unit_float(h2 * 0x7C0D2E4Bu);
    vec3 colour = mix(vec3(1.0, 0.82, 0.65), vec3(0.7, 0.82, 1.0), tint);
    float d = length(p - (cell + 0.5));
    return colour * brightness * (1.0 - smoothstep(0.2, 0.5, d));
}

void main() {
    vec3 dir = world_direction();
    vec3 rgb = vec3(0.0);
    if (u_kind == 1) {
        rgb = mix(u_horizon, u_zenith, clamp(dir.y, 0.0, 1.0));
    } else if (u_kind == 2) {
        rgb = star_field(dir);
    }
    o_color = vec4(rgb, 1.0);
}
