// The model vertex shader of the demo renderer's G-buffer pass (also used
// by the forward transparent pass): view-space position and normal out.

in vec3 a_position;
in vec3 a_normal;
in vec2 a_uv;

uniform mat4 u_model_view;
uniform mat4 u_normal_matrix;   // inverse transpose of u_model_view (upper 3x3 used)
uniform mat4 u_projection;

out vec3 v_position;
out vec3 v_normal;
out vec2 v_uv;

void main() {
    vec4 view_position = u_model_view * vec4(a_position, 1.0);
    v_position = view_position.xyz;
    v_normal = mat3(u_normal_matrix) * a_normal;
    v_uv = a_uv;
    gl_Position = u_projection * view_position;
}
