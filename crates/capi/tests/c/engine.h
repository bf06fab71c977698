/*
 * The C engine of the tests: written the way a maintained C engine on GL 3.3
 * writes its deferred renderer, with the habits such engines have:
 *
 * - six colour attachments: albedo GL_RGB8, two octahedral GL_RG16 normals
 *   (shading and geometric), ORM GL_RGBA8 whose alpha packs bits (a sign
 *   bit beside the occlusion), a linear-depth GL_R16F the lighting reads,
 *   emission GL_RGB16F; a GL_DEPTH24_STENCIL8 texture, stencil 1 where
 *   geometry is;
 * - the camera in a std140 uniform block (`Camera`: projection at byte 0,
 *   view at 64) at binding point 0, written with glBufferSubData each frame;
 * - the G-buffer cleared through another framebuffer (its textures plus a
 *   velocity target of the engine's), attachment by attachment with
 *   glClearBufferfv, linear depth to 65504, before the G-buffer is bound
 *   and drawn without a clear of its own;
 * - lighting into a GL_RGBA16F radiance target (position rebuilt from the
 *   linear depth, the sky drawn where the depth is the clear value), then
 *   a linear tonemap (exposure, clamp) and the sRGB curve in the shader
 *   into an RGBA8 screen.
 *
 * Header-only, included once by each program: engine_host.c (the engine
 * retrofitted in its source, each declaration measured) and
 * engine_program.c (its render loop, run as it is under inject).
 */
#ifndef DMSAA_TEST_ENGINE_H
#define DMSAA_TEST_ENGINE_H

#include "egl_gl.h"
#include <math.h>
#include <stdint.h>
#include <string.h>

#define WIDTH 320
#define HEIGHT 180
#define SUPERSAMPLE 4
#define LIGHTS 6
#define FAR_DEPTH 65504.0f

static const char *version_line = "#version 330 core\n";
/* engine_program.c's --orphan-camera: the camera block written with
 * glBufferData each frame rather than glBufferSubData */
static int camera_orphaned = 0;
/* engine_program.c's --mapped-camera: the camera block written through
 * glMapBufferRange, a path the library does not follow */
static int camera_mapped = 0;
/* engine_program.c's --depth-tested-lighting: the radiance framebuffer
 * shares the G-buffer's depth and stencil, and the lighting is two draws of
 * a quad at the far plane tested against it, as engines light: GL_GREATER
 * passes where geometry is, GL_LEQUAL where the sky is; depth writes off */
static int depth_tested_lighting = 0;
static int failures = 0;

#define CHECK(cond, ...)                                                                           \
    do {                                                                                           \
        if (!(cond)) {                                                                             \
            fprintf(stderr, "check failed: " __VA_ARGS__);                                         \
            fprintf(stderr, "\n");                                                                 \
            failures++;                                                                            \
        }                                                                                          \
    } while (0)

static void gl_errors(const char *where)
{
    for (GLenum e = glGetError(); e != GL_NO_ERROR; e = glGetError()) {
        fprintf(stderr, "GL error 0x%04x after %s\n", e, where);
        failures++;
    }
}

/* ---- shaders ---------------------------------------------------------- */

static const char *model_vs =
    "layout (location = 0) in vec3 in_position;\n"
    "layout (location = 1) in vec3 in_normal;\n"
    "layout (std140) uniform Camera { mat4 u_projection; mat4 u_view; };\n"
    "uniform mat4 u_model;\n"
    "out vec3 v_normal;\n"
    "out vec3 v_view;\n"
    "void main() {\n"
    "    vec4 world = u_model * vec4(in_position, 1.0);\n"
    "    vec4 view = u_view * world;\n"
    "    v_view = view.xyz;\n"
    "    v_normal = mat3(u_view) * mat3(u_model) * in_normal;\n"
    "    gl_Position = u_projection * view;\n"
    "}\n";

static const char *model_fs =
    "in vec3 v_normal;\n"
    "in vec3 v_view;\n"
    "uniform vec3 u_albedo;\n"
    "uniform vec3 u_emission;\n"
    "uniform float u_roughness;\n"
    "layout (location = 0) out vec3 out_albedo;\n"
    "layout (location = 1) out vec2 out_normal;\n"
    "layout (location = 2) out vec2 out_geometric_normal;\n"
    "layout (location = 3) out vec4 out_orm;\n"
    "layout (location = 4) out float out_linear_depth;\n"
    "layout (location = 5) out vec3 out_emission;\n"
    "vec2 octahedral(vec3 n) {\n"
    "    n /= abs(n.x) + abs(n.y) + abs(n.z);\n"
    "    vec2 e = n.z >= 0.0 ? n.xy : (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);\n"
    "    return e * 0.5 + 0.5;\n"
    "}\n"
    "void main() {\n"
    "    vec3 n = normalize(v_normal);\n"
    "    vec3 g = normalize(cross(dFdx(v_view), dFdy(v_view)));\n"
    "    out_albedo = u_albedo;\n"
    "    out_normal = octahedral(n);\n"
    "    out_geometric_normal = octahedral(g);\n"
    "    /* occlusion in the low 7 bits, the normal's facing in the top one */\n"
    "    float occlusion = floor(0.9 * 127.0);\n"
    "    float facing = n.z >= 0.0 ? 128.0 : 0.0;\n"
    "    out_orm = vec4((occlusion + facing) / 255.0, u_roughness, 0.0, 1.0);\n"
    "    out_linear_depth = -v_view.z;\n"
    "    out_emission = u_emission;\n"
    "}\n";

static const char *quad_vs =
    "layout (location = 0) in vec2 in_position;\n"
    "uniform float u_quad_depth;\n"
    "out vec2 v_uv;\n"
    "void main() { v_uv = in_position * 0.5 + 0.5; gl_Position = vec4(in_position, u_quad_depth, 1.0); }\n";

static const char *lighting_fs =
    "in vec2 v_uv;\n"
    "uniform sampler2D g_albedo, g_normal, g_orm, g_linear_depth, g_emission;\n"
    "uniform vec2 u_tan_half;\n"
    "uniform vec3 u_light_position[6];\n"
    "uniform vec3 u_light_colour[6];\n"
    "out vec4 out_radiance;\n"
    "vec3 octahedral_decode(vec2 e) {\n"
    "    e = e * 2.0 - 1.0;\n"
    "    vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));\n"
    "    if (n.z < 0.0) n.xy = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);\n"
    "    return normalize(n);\n"
    "}\n"
    "void main() {\n"
    "    float depth = texture(g_linear_depth, v_uv).r;\n"
    "    if (depth >= 65000.0) { out_radiance = vec4(0.02, 0.03, 0.06, 1.0); return; }\n"
    "    vec3 view = vec3((v_uv * 2.0 - 1.0) * u_tan_half * depth, -depth);\n"
    "    vec3 n = octahedral_decode(texture(g_normal, v_uv).rg);\n"
    "    vec3 albedo = texture(g_albedo, v_uv).rgb;\n"
    "    vec4 orm = texture(g_orm, v_uv);\n"
    "    float occlusion = mod(floor(orm.r * 255.0 + 0.5), 128.0) / 127.0;\n"
    "    vec3 radiance = albedo * 0.05 * occlusion + texture(g_emission, v_uv).rgb;\n"
    "    vec3 to_eye = normalize(-view);\n"
    "    for (int i = 0; i < 6; ++i) {\n"
    "        vec3 l = u_light_position[i] - view;\n"
    "        float d2 = dot(l, l);\n"
    "        l *= inversesqrt(d2);\n"
    "        float shininess = mix(64.0, 4.0, orm.g);\n"
    "        float spec = pow(max(dot(n, normalize(l + to_eye)), 0.0), shininess);\n"
    "        radiance += u_light_colour[i] * (albedo * max(dot(n, l), 0.0) + 0.3 * spec) / (1.0 + d2);\n"
    "    }\n"
    "    out_radiance = vec4(radiance, 1.0);\n"
    "}\n";

/* The engine's tonemap: linear (exposure and clamp), then the sRGB curve. */
static const char *tonemap_fs =
    "in vec2 v_uv;\n"
    "uniform sampler2D u_radiance;\n"
    "uniform float u_exposure;\n"
    "out vec4 out_colour;\n"
    "void main() {\n"
    "    vec3 c = clamp(texture(u_radiance, v_uv).rgb * u_exposure, 0.0, 1.0);\n"
    "    vec3 s = mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308)));\n"
    "    out_colour = vec4(s, 1.0);\n"
    "}\n";

static GLuint compile(GLenum type, const char *body)
{
    GLuint s = glCreateShader(type);
    const char *parts[2] = {version_line, body};
    glShaderSource(s, 2, parts, NULL);
    glCompileShader(s);
    GLint status = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &status);
    if (!status) {
        char log[2048];
        glGetShaderInfoLog(s, sizeof log, NULL, log);
        fprintf(stderr, "shader: %s\n", log);
        failures++;
    }
    return s;
}

static GLuint link(const char *vs, const char *fs)
{
    GLuint p = glCreateProgram(), v = compile(GL_VERTEX_SHADER, vs), f = compile(GL_FRAGMENT_SHADER, fs);
    glAttachShader(p, v);
    glAttachShader(p, f);
    glLinkProgram(p);
    GLint status = 0;
    glGetProgramiv(p, GL_LINK_STATUS, &status);
    if (!status) {
        char log[2048];
        glGetProgramInfoLog(p, sizeof log, NULL, log);
        fprintf(stderr, "link: %s\n", log);
        failures++;
    }
    glDeleteShader(v);
    glDeleteShader(f);
    return p;
}

/* ---- maths ------------------------------------------------------------ */

static void identity(float *m)
{
    memset(m, 0, 16 * sizeof(float));
    m[0] = m[5] = m[10] = m[15] = 1.0f;
}

static void model_matrix(float *m, float x, float y, float z, float angle, float scale)
{
    /* a turn about (1, 0.8, 0.3), then the scale and the position */
    float ax = 1.0f, ay = 0.8f, az = 0.3f, l = sqrtf(ax * ax + ay * ay + az * az);
    ax /= l, ay /= l, az /= l;
    float c = cosf(angle), s = sinf(angle), t = 1.0f - c;
    identity(m);
    m[0] = (t * ax * ax + c) * scale, m[4] = (t * ax * ay - s * az) * scale, m[8] = (t * ax * az + s * ay) * scale;
    m[1] = (t * ax * ay + s * az) * scale, m[5] = (t * ay * ay + c) * scale, m[9] = (t * ay * az - s * ax) * scale;
    m[2] = (t * ax * az - s * ay) * scale, m[6] = (t * ay * az + s * ax) * scale, m[10] = (t * az * az + c) * scale;
    m[12] = x, m[13] = y, m[14] = z;
}

/* ---- the engine ------------------------------------------------------- */

typedef struct {
    int width, height;
    GLuint gbuffer, clear_fbo, hdr_fbo, screen_fbo;
    GLuint albedo, normal, geometric_normal, orm, linear_depth, emission, depth_stencil;
    GLuint velocity, radiance, screen;
    GLuint model_program, lighting_program, tonemap_program;
    GLuint cube_vao, cube_vbo, quad_vao, quad_vbo, camera_ubo;
    float projection[16], view[16], tan_half[2];
} Engine;

static GLuint texture(int w, int h, GLint internal, GLenum format, GLenum type)
{
    GLuint t;
    glGenTextures(1, &t);
    glBindTexture(GL_TEXTURE_2D, t);
    glTexImage2D(GL_TEXTURE_2D, 0, internal, w, h, 0, format, type, NULL);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glBindTexture(GL_TEXTURE_2D, 0);
    return t;
}

static void attach_gbuffer(const Engine *e)
{
    GLuint colours[6] = {e->albedo, e->normal, e->geometric_normal, e->orm, e->linear_depth, e->emission};
    for (int i = 0; i < 6; i++)
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + i, GL_TEXTURE_2D, colours[i], 0);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_TEXTURE_2D, e->depth_stencil, 0);
}

static void engine_init(Engine *e, int w, int h)
{
    memset(e, 0, sizeof *e);
    e->width = w, e->height = h;
    e->albedo = texture(w, h, GL_RGB8, GL_RGB, GL_UNSIGNED_BYTE);
    e->normal = texture(w, h, GL_RG16, GL_RG, GL_UNSIGNED_SHORT);
    e->geometric_normal = texture(w, h, GL_RG16, GL_RG, GL_UNSIGNED_SHORT);
    e->orm = texture(w, h, GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE);
    e->linear_depth = texture(w, h, GL_R16F, GL_RED, GL_HALF_FLOAT);
    e->emission = texture(w, h, GL_RGB16F, GL_RGB, GL_HALF_FLOAT);
    e->depth_stencil = texture(w, h, GL_DEPTH24_STENCIL8, GL_DEPTH_STENCIL, GL_UNSIGNED_INT_24_8);
    e->velocity = texture(w, h, GL_RG16F, GL_RG, GL_HALF_FLOAT);
    e->radiance = texture(w, h, GL_RGBA16F, GL_RGBA, GL_HALF_FLOAT);
    e->screen = texture(w, h, GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE);
    static const GLenum six[6] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2,
                                  GL_COLOR_ATTACHMENT3, GL_COLOR_ATTACHMENT4, GL_COLOR_ATTACHMENT5};
    static const GLenum seven[7] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2,
                                    GL_COLOR_ATTACHMENT3, GL_COLOR_ATTACHMENT4, GL_COLOR_ATTACHMENT5,
                                    GL_COLOR_ATTACHMENT6};
    glGenFramebuffers(1, &e->gbuffer);
    glBindFramebuffer(GL_FRAMEBUFFER, e->gbuffer);
    attach_gbuffer(e);
    glDrawBuffers(6, six);
    CHECK(glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE, "G-buffer incomplete");
    /* the clear framebuffer: the G-buffer's images and the velocity target */
    glGenFramebuffers(1, &e->clear_fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, e->clear_fbo);
    attach_gbuffer(e);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT6, GL_TEXTURE_2D, e->velocity, 0);
    glDrawBuffers(7, seven);
    CHECK(glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE, "clear target incomplete");
    glGenFramebuffers(1, &e->hdr_fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, e->hdr_fbo);
    if (depth_tested_lighting)
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_TEXTURE_2D, e->depth_stencil, 0);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, e->radiance, 0);
    glGenFramebuffers(1, &e->screen_fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, e->screen_fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, e->screen, 0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);

    e->model_program = link(model_vs, model_fs);
    /* the camera block at binding point 0, as the engine's every program */
    glUniformBlockBinding(e->model_program, glGetUniformBlockIndex(e->model_program, "Camera"), 0);
    glGenBuffers(1, &e->camera_ubo);
    glBindBuffer(GL_UNIFORM_BUFFER, e->camera_ubo);
    glBufferData(GL_UNIFORM_BUFFER, 32 * sizeof(float), NULL, GL_DYNAMIC_DRAW);
    glBindBuffer(GL_UNIFORM_BUFFER, 0);
    e->lighting_program = link(quad_vs, lighting_fs);
    e->tonemap_program = link(quad_vs, tonemap_fs);

    /* a unit cube: 6 faces, 2 triangles each, position and normal */
    static const float faces[6][3][3] = {
        {{0, 0, -1}, {-1, 0, 0}, {0, 1, 0}}, {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},
        {{-1, 0, 0}, {0, 0, 1}, {0, 1, 0}},  {{1, 0, 0}, {0, 0, -1}, {0, 1, 0}},
        {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}},  {{0, 1, 0}, {1, 0, 0}, {0, 0, -1}},
    };
    static const float corners[6][2] = {{-1, -1}, {1, -1}, {1, 1}, {1, 1}, {-1, 1}, {-1, -1}};
    float cube[36 * 6];
    int i = 0;
    for (int f = 0; f < 6; f++)
        for (int c = 0; c < 6; c++) {
            for (int k = 0; k < 3; k++)
                cube[i++] = faces[f][0][k] + corners[c][0] * faces[f][1][k] + corners[c][1] * faces[f][2][k];
            for (int k = 0; k < 3; k++)
                cube[i++] = faces[f][0][k];
        }
    glGenVertexArrays(1, &e->cube_vao);
    glGenBuffers(1, &e->cube_vbo);
    glBindVertexArray(e->cube_vao);
    glBindBuffer(GL_ARRAY_BUFFER, e->cube_vbo);
    glBufferData(GL_ARRAY_BUFFER, sizeof cube, cube, GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), (void *)0);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), (void *)(3 * sizeof(float)));
    static const float quad[8] = {-1, -1, 1, -1, -1, 1, 1, 1};
    glGenVertexArrays(1, &e->quad_vao);
    glGenBuffers(1, &e->quad_vbo);
    glBindVertexArray(e->quad_vao);
    glBindBuffer(GL_ARRAY_BUFFER, e->quad_vbo);
    glBufferData(GL_ARRAY_BUFFER, sizeof quad, quad, GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 2 * sizeof(float), (void *)0);
    glBindVertexArray(0);
    glBindBuffer(GL_ARRAY_BUFFER, 0);

    /* camera: 45 degrees, looking down at the grid */
    float aspect = (float)w / (float)h, f = 1.0f / tanf(0.3927f), near = 0.1f, far = 100.0f;
    memset(e->projection, 0, sizeof e->projection);
    e->projection[0] = f / aspect, e->projection[5] = f;
    e->projection[10] = (far + near) / (near - far), e->projection[11] = -1.0f;
    e->projection[14] = 2.0f * far * near / (near - far);
    e->tan_half[0] = aspect / f, e->tan_half[1] = 1.0f / f;
    /* a turn of 0.6 rad about x, then back by 9 */
    float c = cosf(0.6f), s = sinf(0.6f);
    identity(e->view);
    e->view[5] = c, e->view[6] = -s, e->view[9] = s, e->view[10] = c;
    e->view[13] = 0.0f, e->view[14] = -9.0f;
}

static void engine_free(Engine *e)
{
    GLuint fbos[4] = {e->gbuffer, e->clear_fbo, e->hdr_fbo, e->screen_fbo};
    glDeleteFramebuffers(4, fbos);
    GLuint textures[10] = {e->albedo, e->normal, e->geometric_normal, e->orm, e->linear_depth,
                           e->emission, e->depth_stencil, e->velocity, e->radiance, e->screen};
    glDeleteTextures(10, textures);
    glDeleteProgram(e->model_program);
    glDeleteProgram(e->lighting_program);
    glDeleteProgram(e->tonemap_program);
    GLuint vaos[2] = {e->cube_vao, e->quad_vao}, buffers[3] = {e->cube_vbo, e->quad_vbo, e->camera_ubo};
    glDeleteVertexArrays(2, vaos);
    glDeleteBuffers(3, buffers);
}

/* The engine's clear: through its own framebuffer, each target with its value. */
static void clear_gbuffer(const Engine *e)
{
    static const float zero[4] = {0, 0, 0, 0}, up[4] = {0.5f, 0.5f, 0, 0}, far[4] = {FAR_DEPTH, 0, 0, 0};
    static const float orm[4] = {0, 1, 0, 1};
    glBindFramebuffer(GL_FRAMEBUFFER, e->clear_fbo);
    glViewport(0, 0, e->width, e->height);
    glClearBufferfv(GL_COLOR, 0, zero);
    glClearBufferfv(GL_COLOR, 1, up);
    glClearBufferfv(GL_COLOR, 2, up);
    glClearBufferfv(GL_COLOR, 3, orm);
    glClearBufferfv(GL_COLOR, 4, far);
    glClearBufferfv(GL_COLOR, 5, zero);
    glClearBufferfv(GL_COLOR, 6, zero);
    glClearBufferfi(GL_DEPTH_STENCIL, 0, 1.0f, 0);
}

/* The geometry pass into `target`, no clear of its own; stencil 1 where drawn. */
static void geometry_pass(const Engine *e, GLuint target)
{
    glBindFramebuffer(GL_FRAMEBUFFER, target);
    glViewport(0, 0, e->width, e->height);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glEnable(GL_STENCIL_TEST);
    glStencilFunc(GL_ALWAYS, 1, 0xFF);
    glStencilOp(GL_KEEP, GL_KEEP, GL_REPLACE);
    glUseProgram(e->model_program);
    /* the frame's camera written into its block: in place, or (with
     * camera_orphaned) the whole block given new storage each frame, as
     * engines orphan a buffer the GPU may still read */
    glBindBuffer(GL_UNIFORM_BUFFER, e->camera_ubo);
    if (camera_mapped) {
        float *mapped = (float *)glMapBufferRange(GL_UNIFORM_BUFFER, 0, 32 * sizeof(float),
                                                  GL_MAP_WRITE_BIT | GL_MAP_INVALIDATE_BUFFER_BIT);
        CHECK(mapped != NULL, "the camera block could not be mapped");
        if (mapped) {
            memcpy(mapped, e->projection, sizeof e->projection);
            memcpy(mapped + 16, e->view, sizeof e->view);
        }
        glUnmapBuffer(GL_UNIFORM_BUFFER);
    } else if (camera_orphaned) {
        float camera[32];
        memcpy(camera, e->projection, sizeof e->projection);
        memcpy(camera + 16, e->view, sizeof e->view);
        glBufferData(GL_UNIFORM_BUFFER, sizeof camera, camera, GL_STREAM_DRAW);
    } else {
        glBufferSubData(GL_UNIFORM_BUFFER, 0, 16 * sizeof(float), e->projection);
        glBufferSubData(GL_UNIFORM_BUFFER, 16 * sizeof(float), 16 * sizeof(float), e->view);
    }
    glBindBuffer(GL_UNIFORM_BUFFER, 0);
    glBindBufferBase(GL_UNIFORM_BUFFER, 0, e->camera_ubo);
    glBindVertexArray(e->cube_vao);
    for (int i = 0; i < 12; i++) {
        float m[16];
        float x = (float)(i % 4) * 2.2f - 3.3f, z = (float)(i / 4) * 2.4f - 2.4f;
        model_matrix(m, x, 0.15f * (float)(i % 3), z, 0.4f + 0.7f * (float)i, 0.55f);
        glUniformMatrix4fv(glGetUniformLocation(e->model_program, "u_model"), 1, GL_FALSE, m);
        glUniform3f(glGetUniformLocation(e->model_program, "u_albedo"), 0.3f + 0.05f * (float)i,
                    0.8f - 0.05f * (float)i, 0.4f + 0.15f * (float)(i % 3));
        float glow_ = i % 5 == 0 ? 2.0f : 0.0f;
        glUniform3f(glGetUniformLocation(e->model_program, "u_emission"), glow_, 0.6f * glow_, 0.2f * glow_);
        glUniform1f(glGetUniformLocation(e->model_program, "u_roughness"), 0.2f + 0.06f * (float)i);
        glDrawArrays(GL_TRIANGLES, 0, 36);
    }
    glBindVertexArray(0);
    glDisable(GL_STENCIL_TEST);
    glDisable(GL_DEPTH_TEST);
}

static void bind_gbuffer_textures(const Engine *e)
{
    GLuint t[5] = {e->albedo, e->normal, e->orm, e->linear_depth, e->emission};
    const char *names[5] = {"g_albedo", "g_normal", "g_orm", "g_linear_depth", "g_emission"};
    for (int i = 0; i < 5; i++) {
        glActiveTexture(GL_TEXTURE0 + i);
        glBindTexture(GL_TEXTURE_2D, t[i]);
        glUniform1i(glGetUniformLocation(e->lighting_program, names[i]), i);
    }
    glActiveTexture(GL_TEXTURE0);
}

/* The lighting pass: every pixel of `target` (the radiance target's
 * framebuffer, or the retrofit's own target for the second layer). */
static void lighting_into(const Engine *e, GLuint target)
{
    static const float positions[LIGHTS][3] = {{-2.5f, 1.5f, -6.0f}, {2.0f, 1.0f, -8.0f}, {0.0f, -1.0f, -7.0f},
                                               {-1.0f, 2.5f, -10.0f}, {3.0f, 2.0f, -11.0f}, {-3.0f, -0.5f, -9.0f}};
    static const float colours[LIGHTS][3] = {{4, 3, 2}, {2, 3, 5}, {3, 3, 3}, {5, 2, 2}, {2, 5, 2}, {3, 2, 4}};
    glBindFramebuffer(GL_FRAMEBUFFER, target);
    glViewport(0, 0, e->width, e->height);
    glUseProgram(e->lighting_program);
    bind_gbuffer_textures(e);
    glUniform2f(glGetUniformLocation(e->lighting_program, "u_tan_half"), e->tan_half[0], e->tan_half[1]);
    for (int i = 0; i < LIGHTS; i++) {
        char name[64];
        snprintf(name, sizeof name, "u_light_position[%d]", i);
        glUniform3f(glGetUniformLocation(e->lighting_program, name), positions[i][0], positions[i][1], positions[i][2]);
        snprintf(name, sizeof name, "u_light_colour[%d]", i);
        glUniform3f(glGetUniformLocation(e->lighting_program, name), colours[i][0], colours[i][1], colours[i][2]);
    }
    glBindVertexArray(e->quad_vao);
    if (depth_tested_lighting) {
        GLint quad_depth = glGetUniformLocation(e->lighting_program, "u_quad_depth");
        glUniform1f(quad_depth, 1.0f);
        glEnable(GL_DEPTH_TEST);
        glDepthMask(GL_FALSE);
        glDepthFunc(GL_GREATER); /* where geometry is */
        glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
        glDepthFunc(GL_LEQUAL); /* where the sky is */
        glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
        glDepthFunc(GL_LESS);
        glDepthMask(GL_TRUE);
        glDisable(GL_DEPTH_TEST);
        glUniform1f(quad_depth, 0.0f);
    } else {
        glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
    }
    glBindVertexArray(0);
}

static void lighting_pass(const Engine *e) { lighting_into(e, e->hdr_fbo); }

static void tonemap_pass(const Engine *e)
{
    glBindFramebuffer(GL_FRAMEBUFFER, e->screen_fbo);
    glViewport(0, 0, e->width, e->height);
    glUseProgram(e->tonemap_program);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, e->radiance);
    glUniform1i(glGetUniformLocation(e->tonemap_program, "u_radiance"), 0);
    glUniform1f(glGetUniformLocation(e->tonemap_program, "u_exposure"), 0.8f);
    glBindVertexArray(e->quad_vao);
    glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
    glBindVertexArray(0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

static unsigned char *read_rgba(GLuint fbo, GLenum buffer, int w, int h, GLenum format, GLenum type, int bytes)
{
    unsigned char *pixels = malloc((size_t)w * (size_t)h * (size_t)bytes);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo);
    glReadBuffer(buffer);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, w, h, format, type, pixels);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    return pixels;
}

/* `name` in `dir`, or the path `name` where `dir` is NULL. */
static void write_file(const char *dir, const char *name, const void *data, size_t size)
{
    char path[4096];
    snprintf(path, sizeof path, "%s%s%s", dir ? dir : "", dir ? "/" : "", name);
    FILE *f = fopen(path, "wb");
    CHECK(f != NULL, "cannot write %s", path);
    if (f) {
        fwrite(data, 1, size, f);
        fclose(f);
    }
}

static void write_screen(const Engine *e, const char *dir, const char *name)
{
    unsigned char *p = read_rgba(e->screen_fbo, GL_COLOR_ATTACHMENT0, e->width, e->height, GL_RGBA,
                                 GL_UNSIGNED_BYTE, 4);
    write_file(dir, name, p, (size_t)e->width * (size_t)e->height * 4);
    free(p);
}

/* Edges of the engine's own frame: a neighbour's linear depth 2 % away, or
 * its octahedral normal another. */
static void write_edges(const Engine *e, const char *dir)
{
    int w = e->width, h = e->height;
    float *depth = (float *)read_rgba(e->gbuffer, GL_COLOR_ATTACHMENT4, w, h, GL_RED, GL_FLOAT, 4);
    unsigned short *normal =
        (unsigned short *)read_rgba(e->gbuffer, GL_COLOR_ATTACHMENT1, w, h, GL_RG, GL_UNSIGNED_SHORT, 4);
    unsigned char *mask = calloc((size_t)w * (size_t)h, 1);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            int i = y * w + x;
            static const int d[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
            for (int k = 0; k < 4; k++) {
                int nx = x + d[k][0], ny = y + d[k][1];
                if (nx < 0 || ny < 0 || nx >= w || ny >= h)
                    continue;
                int j = ny * w + nx;
                float a = depth[i], b = depth[j];
                int normal_step = abs((int)normal[2 * i] - (int)normal[2 * j]) > 2000 ||
                                  abs((int)normal[2 * i + 1] - (int)normal[2 * j + 1]) > 2000;
                if (fabsf(a - b) > 0.02f * fminf(a, b) || normal_step)
                    mask[i] = 255;
            }
        }
    write_file(dir, "edges.mask", mask, (size_t)w * (size_t)h);
    free(mask);
    free(normal);
    free(depth);
}

static double decode(unsigned char v)
{
    double c = v / 255.0;
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

static unsigned char encode(double l)
{
    double c = l <= 0.0031308 ? l * 12.92 : 1.055 * pow(l, 1.0 / 2.4) - 0.055;
    c = c < 0.0 ? 0.0 : c > 1.0 ? 1.0 : c;
    return (unsigned char)lround(c * 255.0);
}

static void write_reference(const char *dir)
{
    Engine big;
    int w = WIDTH * SUPERSAMPLE, h = HEIGHT * SUPERSAMPLE;
    engine_init(&big, w, h);
    clear_gbuffer(&big);
    geometry_pass(&big, big.gbuffer);
    lighting_pass(&big);
    tonemap_pass(&big);
    unsigned char *p = read_rgba(big.screen_fbo, GL_COLOR_ATTACHMENT0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, 4);
    unsigned char *small = malloc((size_t)WIDTH * HEIGHT * 4);
    for (int y = 0; y < HEIGHT; y++)
        for (int x = 0; x < WIDTH; x++)
            for (int c = 0; c < 4; c++) {
                double sum = 0.0;
                for (int dy = 0; dy < SUPERSAMPLE; dy++)
                    for (int dx = 0; dx < SUPERSAMPLE; dx++) {
                        unsigned char v = p[((size_t)(y * SUPERSAMPLE + dy) * (size_t)w + (size_t)(x * SUPERSAMPLE + dx)) * 4 + c];
                        sum += c == 3 ? v / 255.0 : decode(v);
                    }
                double mean = sum / (SUPERSAMPLE * SUPERSAMPLE);
                small[((size_t)y * WIDTH + x) * 4 + c] = c == 3 ? (unsigned char)lround(mean * 255.0) : encode(mean);
            }
    write_file(dir, "reference.rgba", small, (size_t)WIDTH * HEIGHT * 4);
    free(small);
    free(p);
    engine_free(&big);
}

#endif
