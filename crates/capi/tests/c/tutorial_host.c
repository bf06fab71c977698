/*
 * A C host written the way the LearnOpenGL "Deferred Shading" chapter
 * writes its engine: gPosition and gNormal RGBA16F textures, gAlbedoSpec
 * with the unsized GL_RGBA / GL_UNSIGNED_BYTE, a GL_DEPTH_COMPONENT
 * renderbuffer, glDrawBuffers of the three; a geometry pass writing
 * world-space positions and normals, a lighting pass over 32 point lights
 * on a screen quad, then the chapter's forward part (the G-buffer's depth
 * blitted to the screen, the lights drawn as small cubes). Its GL comes
 * from its own loader (egl_gl.h).
 *
 * Departures, each for the test's sake: the objects are cubes with one
 * diffuse colour and specular intensity each (no model files), the camera
 * looks down on the 3x3 grid so that every object is in view, the
 * "screen" is a framebuffer of the host's own (no window), and the frame
 * is drawn once.
 *
 * It renders the frame four ways and writes each lit image, raw RGBA8
 * rows bottom-up, into the folder given as its argument: without MSAA
 * (none.rgba), with the retrofit (msaa.rgba: the two calls, and the light
 * cubes through the forward target's two), with two layers (layers.rgba:
 * and the three second-layer calls), and its own 16x supersampled image
 * (reference.rgba: the frame at 4x the width and height, averaged 4x4 in
 * the light a screen emits: sRGB decoded, averaged, encoded). It checks
 * that the GL state around every library call is unchanged, that the host's objects survive, and that
 * nothing of the library's is left after dmsaa_destroy. It exits non-zero,
 * with a line saying why, on any failure.
 *
 * Usage: tutorial_host OUT_DIR
 */
#include "deferred_msaa.h"
#include "egl_gl.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

#define SCR_WIDTH 320
#define SCR_HEIGHT 180
#define SUPERSAMPLE 4
#define NR_LIGHTS 32

/* The tutorial's shaders are GLSL 3.30; on a 3.2 context (the CI's
 * floor) the same text compiles as 1.50 with the extension that gives it
 * its layout locations. shader_program puts the line in front. */
static const char *glsl_version_line = "#version 330 core\n";

static const char *g_buffer_vs =
    "layout (location = 0) in vec3 aPos;\n"
    "layout (location = 1) in vec3 aNormal;\n"
    "layout (location = 2) in vec2 aTexCoords;\n"
    "out vec3 FragPos;\n"
    "out vec2 TexCoords;\n"
    "out vec3 Normal;\n"
    "uniform mat4 model;\n"
    "uniform mat4 view;\n"
    "uniform mat4 projection;\n"
    "void main()\n"
    "{\n"
    "    vec4 worldPos = model * vec4(aPos, 1.0);\n"
    "    FragPos = worldPos.xyz;\n"
    "    TexCoords = aTexCoords;\n"
    "    mat3 normalMatrix = transpose(inverse(mat3(model)));\n"
    "    Normal = normalMatrix * aNormal;\n"
    "    gl_Position = projection * view * worldPos;\n"
    "}\n";

static const char *g_buffer_fs =
    "layout (location = 0) out vec3 gPosition;\n"
    "layout (location = 1) out vec3 gNormal;\n"
    "layout (location = 2) out vec4 gAlbedoSpec;\n"
    "in vec2 TexCoords;\n"
    "in vec3 FragPos;\n"
    "in vec3 Normal;\n"
    "uniform vec3 diffuseColor;\n"
    "uniform float specularIntensity;\n"
    "void main()\n"
    "{\n"
    "    // store the fragment position vector in the first gbuffer texture\n"
    "    gPosition = FragPos;\n"
    "    // also store the per-fragment normals into the gbuffer\n"
    "    gNormal = normalize(Normal);\n"
    "    // and the diffuse per-fragment color\n"
    "    gAlbedoSpec.rgb = diffuseColor;\n"
    "    // store specular intensity in gAlbedoSpec's alpha component\n"
    "    gAlbedoSpec.a = specularIntensity;\n"
    "}\n";

static const char *deferred_shading_vs =
    "layout (location = 0) in vec3 aPos;\n"
    "layout (location = 1) in vec2 aTexCoords;\n"
    "out vec2 TexCoords;\n"
    "void main()\n"
    "{\n"
    "    TexCoords = aTexCoords;\n"
    "    gl_Position = vec4(aPos, 1.0);\n"
    "}\n";

static const char *deferred_shading_fs =
    "out vec4 FragColor;\n"
    "in vec2 TexCoords;\n"
    "uniform sampler2D gPosition;\n"
    "uniform sampler2D gNormal;\n"
    "uniform sampler2D gAlbedoSpec;\n"
    "struct Light {\n"
    "    vec3 Position;\n"
    "    vec3 Color;\n"
    "    float Linear;\n"
    "    float Quadratic;\n"
    "};\n"
    "const int NR_LIGHTS = 32;\n"
    "uniform Light lights[NR_LIGHTS];\n"
    "uniform vec3 viewPos;\n"
    "void main()\n"
    "{\n"
    "    // retrieve data from gbuffer\n"
    "    vec3 FragPos = texture(gPosition, TexCoords).rgb;\n"
    "    vec3 Normal = texture(gNormal, TexCoords).rgb;\n"
    "    vec3 Diffuse = texture(gAlbedoSpec, TexCoords).rgb;\n"
    "    float Specular = texture(gAlbedoSpec, TexCoords).a;\n"
    "    // then calculate lighting as usual\n"
    "    vec3 lighting  = Diffuse * 0.1; // hard-coded ambient component\n"
    "    vec3 viewDir  = normalize(viewPos - FragPos);\n"
    "    for(int i = 0; i < NR_LIGHTS; ++i)\n"
    "    {\n"
    "        // diffuse\n"
    "        vec3 lightDir = normalize(lights[i].Position - FragPos);\n"
    "        vec3 diffuse = max(dot(Normal, lightDir), 0.0) * Diffuse * lights[i].Color;\n"
    "        // specular\n"
    "        vec3 halfwayDir = normalize(lightDir + viewDir);\n"
    "        float spec = pow(max(dot(Normal, halfwayDir), 0.0), 16.0);\n"
    "        vec3 specular = lights[i].Color * spec * Specular;\n"
    "        // attenuation\n"
    "        float distance = length(lights[i].Position - FragPos);\n"
    "        float attenuation = 1.0 / (1.0 + lights[i].Linear * distance + lights[i].Quadratic * distance * distance);\n"
    "        diffuse *= attenuation;\n"
    "        specular *= attenuation;\n"
    "        lighting += diffuse + specular;\n"
    "    }\n"
    "    FragColor = vec4(lighting, 1.0);\n"
    "}\n";

static const char *light_box_vs =
    "layout (location = 0) in vec3 aPos;\n"
    "uniform mat4 projection;\n"
    "uniform mat4 view;\n"
    "uniform mat4 model;\n"
    "void main()\n"
    "{\n"
    "    gl_Position = projection * view * model * vec4(aPos, 1.0);\n"
    "}\n";

static const char *light_box_fs =
    "layout (location = 0) out vec4 FragColor;\n"
    "uniform vec3 lightColor;\n"
    "void main()\n"
    "{\n"
    "    FragColor = vec4(lightColor, 1.0);\n"
    "}\n";

static int failures = 0;

#define CHECK(cond, ...)                                                       \
    do {                                                                       \
        if (!(cond)) {                                                         \
            fprintf(stderr, "FAIL: " __VA_ARGS__);                             \
            fprintf(stderr, "\n");                                             \
            failures++;                                                        \
        }                                                                      \
    } while (0)

/* --- the tutorial's Shader class, as C functions --------------------- */

static GLuint compile(GLenum type, const char *source)
{
    GLuint shader = glCreateShader(type);
    const char *sources[2] = {glsl_version_line, source};
    glShaderSource(shader, 2, sources, NULL);
    glCompileShader(shader);
    GLint success;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &success);
    if (!success) {
        char log[1024];
        glGetShaderInfoLog(shader, sizeof log, NULL, log);
        fprintf(stderr, "ERROR::SHADER_COMPILATION_ERROR\n%s\n", log);
        exit(1);
    }
    return shader;
}

static GLuint shader_program(const char *vs, const char *fs)
{
    GLuint vertex = compile(GL_VERTEX_SHADER, vs);
    GLuint fragment = compile(GL_FRAGMENT_SHADER, fs);
    GLuint id = glCreateProgram();
    glAttachShader(id, vertex);
    glAttachShader(id, fragment);
    glLinkProgram(id);
    GLint success;
    glGetProgramiv(id, GL_LINK_STATUS, &success);
    if (!success) {
        char log[1024];
        glGetProgramInfoLog(id, sizeof log, NULL, log);
        fprintf(stderr, "ERROR::PROGRAM_LINKING_ERROR\n%s\n", log);
        exit(1);
    }
    glDeleteShader(vertex);
    glDeleteShader(fragment);
    return id;
}

static void set_mat4(GLuint id, const char *name, const float *m)
{
    glUniformMatrix4fv(glGetUniformLocation(id, name), 1, GL_FALSE, m);
}

static void set_vec3(GLuint id, const char *name, float x, float y, float z)
{
    glUniform3f(glGetUniformLocation(id, name), x, y, z);
}

static void set_float(GLuint id, const char *name, float v)
{
    glUniform1f(glGetUniformLocation(id, name), v);
}

static void set_int(GLuint id, const char *name, int v)
{
    glUniform1i(glGetUniformLocation(id, name), v);
}

/* --- glm, the little of it the tutorial uses (column-major) ----------- */

static void mat4_identity(float *m)
{
    memset(m, 0, 16 * sizeof(float));
    m[0] = m[5] = m[10] = m[15] = 1.0f;
}

static void perspective(float *m, float fovy, float aspect, float near, float far)
{
    float f = 1.0f / tanf(fovy / 2.0f);
    memset(m, 0, 16 * sizeof(float));
    m[0] = f / aspect;
    m[5] = f;
    m[10] = (far + near) / (near - far);
    m[11] = -1.0f;
    m[14] = 2.0f * far * near / (near - far);
}

static void look_at(float *m, const float *eye, const float *center)
{
    float f[3] = {center[0] - eye[0], center[1] - eye[1], center[2] - eye[2]};
    float fl = sqrtf(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    for (int i = 0; i < 3; i++)
        f[i] /= fl;
    /* s = f x up, up = +y */
    float s[3] = {-f[2], 0.0f, f[0]};
    float sl = sqrtf(s[0] * s[0] + s[2] * s[2]);
    s[0] /= sl;
    s[2] /= sl;
    float u[3] = {s[1] * f[2] - s[2] * f[1], s[2] * f[0] - s[0] * f[2], s[0] * f[1] - s[1] * f[0]};
    mat4_identity(m);
    for (int i = 0; i < 3; i++) {
        m[i * 4 + 0] = s[i];
        m[i * 4 + 1] = u[i];
        m[i * 4 + 2] = -f[i];
    }
    m[12] = -(s[0] * eye[0] + s[1] * eye[1] + s[2] * eye[2]);
    m[13] = -(u[0] * eye[0] + u[1] * eye[1] + u[2] * eye[2]);
    m[14] = f[0] * eye[0] + f[1] * eye[1] + f[2] * eye[2];
}

/* translate * rotate(angle, axis) * scale, as the tutorial composes it. */
static void model_matrix(float *m, const float *position, float angle, const float *axis, float scale)
{
    float l = sqrtf(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    float x = axis[0] / l, y = axis[1] / l, z = axis[2] / l;
    float c = cosf(angle), s = sinf(angle), t = 1.0f - c;
    float r[16] = {
        t * x * x + c,     t * x * y + s * z, t * x * z - s * y, 0.0f,
        t * x * y - s * z, t * y * y + c,     t * y * z + s * x, 0.0f,
        t * x * z + s * y, t * y * z - s * x, t * z * z + c,     0.0f,
        0.0f,              0.0f,              0.0f,              1.0f,
    };
    for (int i = 0; i < 12; i++)
        r[i] *= scale;
    r[12] = position[0];
    r[13] = position[1];
    r[14] = position[2];
    memcpy(m, r, sizeof r);
}

/* --- the engine --------------------------------------------------------- */

typedef struct {
    int width, height;
    GLuint gBuffer, gPosition, gNormal, gAlbedoSpec, rboDepth;
    GLuint screen, screenColor, screenDepth; /* the window's framebuffer */
    GLuint shaderGeometryPass, shaderLightingPass, shaderLightBox;
    GLuint cubeVAO, cubeVBO, quadVAO, quadVBO;
    float projection[16], view[16];
    float lightPositions[NR_LIGHTS][3], lightColors[NR_LIGHTS][3];
} Engine;

static const float objectPositions[9][3] = {
    {-3.0f, -0.5f, -3.0f}, {0.0f, -0.5f, -3.0f}, {3.0f, -0.5f, -3.0f},
    {-3.0f, -0.5f, 0.0f},  {0.0f, -0.5f, 0.0f},  {3.0f, -0.5f, 0.0f},
    {-3.0f, -0.5f, 3.0f},  {0.0f, -0.5f, 3.0f},  {3.0f, -0.5f, 3.0f},
};
static const float cameraPosition[3] = {0.0f, 4.0f, 9.0f};
static const float cameraTarget[3] = {0.0f, -0.5f, 0.0f};

static GLuint color_buffer(int w, int h, GLint internal, GLenum type, GLenum attachment)
{
    GLuint t;
    glGenTextures(1, &t);
    glBindTexture(GL_TEXTURE_2D, t);
    glTexImage2D(GL_TEXTURE_2D, 0, internal, w, h, 0, GL_RGBA, type, NULL);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glFramebufferTexture2D(GL_FRAMEBUFFER, attachment, GL_TEXTURE_2D, t, 0);
    return t;
}

/* The cube of the tutorial's renderCube(): 36 vertices of position,
 * normal and texture coordinates, counter-clockwise from outside. */
static void cube_vertices(float *out)
{
    static const float faces[6][3][3] = {
        /* normal, u axis, v axis */
        {{0, 0, -1}, {-1, 0, 0}, {0, 1, 0}}, {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},
        {{-1, 0, 0}, {0, 0, 1}, {0, 1, 0}},  {{1, 0, 0}, {0, 0, -1}, {0, 1, 0}},
        {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}},  {{0, 1, 0}, {1, 0, 0}, {0, 0, -1}},
    };
    static const float corners[6][2] = {{-1, -1}, {1, -1}, {1, 1}, {1, 1}, {-1, 1}, {-1, -1}};
    int k = 0;
    for (int f = 0; f < 6; f++)
        for (int c = 0; c < 6; c++) {
            for (int i = 0; i < 3; i++)
                out[k++] = faces[f][0][i] + corners[c][0] * faces[f][1][i] + corners[c][1] * faces[f][2][i];
            for (int i = 0; i < 3; i++)
                out[k++] = faces[f][0][i];
            out[k++] = (corners[c][0] + 1.0f) / 2.0f;
            out[k++] = (corners[c][1] + 1.0f) / 2.0f;
        }
}

static void engine_init(Engine *e, int width, int height)
{
    memset(e, 0, sizeof *e);
    e->width = width;
    e->height = height;
    /* glfw's window and framebuffer_size_callback */
    glViewport(0, 0, width, height);
    glEnable(GL_DEPTH_TEST);

    e->shaderGeometryPass = shader_program(g_buffer_vs, g_buffer_fs);
    e->shaderLightingPass = shader_program(deferred_shading_vs, deferred_shading_fs);
    e->shaderLightBox = shader_program(light_box_vs, light_box_fs);

    /* the screen the default framebuffer stands for */
    glGenFramebuffers(1, &e->screen);
    glBindFramebuffer(GL_FRAMEBUFFER, e->screen);
    glGenRenderbuffers(1, &e->screenColor);
    glBindRenderbuffer(GL_RENDERBUFFER, e->screenColor);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, e->screenColor);
    glGenRenderbuffers(1, &e->screenDepth);
    glBindRenderbuffer(GL_RENDERBUFFER, e->screenDepth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT, width, height);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, e->screenDepth);

    /* configure g-buffer framebuffer */
    glGenFramebuffers(1, &e->gBuffer);
    glBindFramebuffer(GL_FRAMEBUFFER, e->gBuffer);
    /* position color buffer */
    e->gPosition = color_buffer(width, height, GL_RGBA16F, GL_FLOAT, GL_COLOR_ATTACHMENT0);
    /* normal color buffer */
    e->gNormal = color_buffer(width, height, GL_RGBA16F, GL_FLOAT, GL_COLOR_ATTACHMENT1);
    /* color + specular color buffer */
    e->gAlbedoSpec = color_buffer(width, height, GL_RGBA, GL_UNSIGNED_BYTE, GL_COLOR_ATTACHMENT2);
    /* tell OpenGL which color attachments we'll use (of this framebuffer) for rendering */
    unsigned int attachments[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
    glDrawBuffers(3, attachments);
    /* create and attach depth buffer (renderbuffer) */
    glGenRenderbuffers(1, &e->rboDepth);
    glBindRenderbuffer(GL_RENDERBUFFER, e->rboDepth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT, width, height);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, e->rboDepth);
    /* finally check if framebuffer is complete */
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
        fprintf(stderr, "Framebuffer not complete!\n");
        exit(1);
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);

    /* lighting info */
    srand(13);
    for (unsigned int i = 0; i < NR_LIGHTS; i++) {
        /* calculate slightly random offsets */
        e->lightPositions[i][0] = (float)(((rand() % 100) / 100.0) * 6.0 - 3.0);
        e->lightPositions[i][1] = (float)(((rand() % 100) / 100.0) * 6.0 - 4.0);
        e->lightPositions[i][2] = (float)(((rand() % 100) / 100.0) * 6.0 - 3.0);
        /* also calculate random color */
        e->lightColors[i][0] = (float)(((rand() % 100) / 200.0f) + 0.5); /* between 0.5 and 1.0 */
        e->lightColors[i][1] = (float)(((rand() % 100) / 200.0f) + 0.5);
        e->lightColors[i][2] = (float)(((rand() % 100) / 200.0f) + 0.5);
    }

    /* shader configuration */
    glUseProgram(e->shaderLightingPass);
    set_int(e->shaderLightingPass, "gPosition", 0);
    set_int(e->shaderLightingPass, "gNormal", 1);
    set_int(e->shaderLightingPass, "gAlbedoSpec", 2);

    /* renderCube()'s and renderQuad()'s buffers */
    float cube[36 * 8];
    cube_vertices(cube);
    glGenVertexArrays(1, &e->cubeVAO);
    glGenBuffers(1, &e->cubeVBO);
    glBindBuffer(GL_ARRAY_BUFFER, e->cubeVBO);
    glBufferData(GL_ARRAY_BUFFER, sizeof cube, cube, GL_STATIC_DRAW);
    glBindVertexArray(e->cubeVAO);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 8 * sizeof(float), (void *)0);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 8 * sizeof(float), (void *)(3 * sizeof(float)));
    glEnableVertexAttribArray(2);
    glVertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, 8 * sizeof(float), (void *)(6 * sizeof(float)));
    static const float quad[] = {
        /* positions        texture Coords */
        -1.0f, 1.0f,  0.0f, 0.0f, 1.0f,
        -1.0f, -1.0f, 0.0f, 0.0f, 0.0f,
        1.0f,  1.0f,  0.0f, 1.0f, 1.0f,
        1.0f,  -1.0f, 0.0f, 1.0f, 0.0f,
    };
    glGenVertexArrays(1, &e->quadVAO);
    glGenBuffers(1, &e->quadVBO);
    glBindVertexArray(e->quadVAO);
    glBindBuffer(GL_ARRAY_BUFFER, e->quadVBO);
    glBufferData(GL_ARRAY_BUFFER, sizeof quad, quad, GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 5 * sizeof(float), (void *)0);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 2, GL_FLOAT, GL_FALSE, 5 * sizeof(float), (void *)(3 * sizeof(float)));
    glBindVertexArray(0);

    perspective(e->projection, 45.0f * 3.14159265f / 180.0f, (float)width / (float)height, 0.1f, 100.0f);
    look_at(e->view, cameraPosition, cameraTarget);
    glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
}

/* 1. geometry pass: render scene's geometry/color data into gbuffer
 * (`target`: the G-buffer, or the retrofit's framebuffer in its place) */
static void geometry_pass(Engine *e, GLuint target)
{
    glBindFramebuffer(GL_FRAMEBUFFER, target);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glUseProgram(e->shaderGeometryPass);
    set_mat4(e->shaderGeometryPass, "projection", e->projection);
    set_mat4(e->shaderGeometryPass, "view", e->view);
    glBindVertexArray(e->cubeVAO);
    for (unsigned int i = 0; i < 9; i++) {
        static const float axis[3] = {1.0f, 0.8f, 0.3f};
        float model[16];
        model_matrix(model, objectPositions[i], 0.35f + 0.6f * (float)i, axis, 0.6f);
        set_mat4(e->shaderGeometryPass, "model", model);
        set_vec3(e->shaderGeometryPass, "diffuseColor", 0.45f + 0.06f * (float)i,
                 0.85f - 0.05f * (float)i, 0.5f + 0.04f * (float)(i % 3));
        set_float(e->shaderGeometryPass, "specularIntensity", 0.25f + 0.08f * (float)i);
        glDrawArrays(GL_TRIANGLES, 0, 36);
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

/* 2. lighting pass: calculate lighting by iterating over a screen filled
 * quad pixel-by-pixel using the gbuffer's content. */
static void lighting_pass(Engine *e)
{
    glBindFramebuffer(GL_FRAMEBUFFER, e->screen);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glUseProgram(e->shaderLightingPass);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, e->gPosition);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, e->gNormal);
    glActiveTexture(GL_TEXTURE2);
    glBindTexture(GL_TEXTURE_2D, e->gAlbedoSpec);
    /* send light relevant uniforms */
    char name[64];
    for (unsigned int i = 0; i < NR_LIGHTS; i++) {
        snprintf(name, sizeof name, "lights[%u].Position", i);
        set_vec3(e->shaderLightingPass, name, e->lightPositions[i][0], e->lightPositions[i][1],
                 e->lightPositions[i][2]);
        snprintf(name, sizeof name, "lights[%u].Color", i);
        set_vec3(e->shaderLightingPass, name, e->lightColors[i][0], e->lightColors[i][1],
                 e->lightColors[i][2]);
        /* update attenuation parameters and calculate radius */
        const float linear = 0.7f;
        const float quadratic = 1.8f;
        snprintf(name, sizeof name, "lights[%u].Linear", i);
        set_float(e->shaderLightingPass, name, linear);
        snprintf(name, sizeof name, "lights[%u].Quadratic", i);
        set_float(e->shaderLightingPass, name, quadratic);
    }
    set_vec3(e->shaderLightingPass, "viewPos", cameraPosition[0], cameraPosition[1], cameraPosition[2]);
    /* finally render quad */
    glBindVertexArray(e->quadVAO);
    glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
    glBindVertexArray(0);
}

/* 2.5. copy content of geometry's depth buffer to default framebuffer's
 * depth buffer, then 3. render lights on top of scene (into `target`: the
 * screen, or the library's forward target in its place). */
static void forward_pass_into(Engine *e, GLuint target)
{
    glBindFramebuffer(GL_READ_FRAMEBUFFER, e->gBuffer);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, e->screen);
    glBlitFramebuffer(0, 0, e->width, e->height, 0, 0, e->width, e->height, GL_DEPTH_BUFFER_BIT,
                      GL_NEAREST);
    glBindFramebuffer(GL_FRAMEBUFFER, target);
    glUseProgram(e->shaderLightBox);
    set_mat4(e->shaderLightBox, "projection", e->projection);
    set_mat4(e->shaderLightBox, "view", e->view);
    glBindVertexArray(e->cubeVAO);
    for (unsigned int i = 0; i < NR_LIGHTS; i++) {
        static const float axis[3] = {0.0f, 1.0f, 0.0f};
        float model[16];
        model_matrix(model, e->lightPositions[i], 0.0f, axis, 0.125f);
        set_mat4(e->shaderLightBox, "model", model);
        set_vec3(e->shaderLightBox, "lightColor", e->lightColors[i][0], e->lightColors[i][1],
                 e->lightColors[i][2]);
        glDrawArrays(GL_TRIANGLES, 0, 36);
    }
    glBindVertexArray(0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

static void forward_pass(Engine *e)
{
    forward_pass_into(e, e->screen);
}

static void engine_free(Engine *e)
{
    glDeleteProgram(e->shaderGeometryPass);
    glDeleteProgram(e->shaderLightingPass);
    glDeleteProgram(e->shaderLightBox);
    glDeleteVertexArrays(1, &e->cubeVAO);
    glDeleteVertexArrays(1, &e->quadVAO);
    glDeleteBuffers(1, &e->cubeVBO);
    glDeleteBuffers(1, &e->quadVBO);
    GLuint textures[3] = {e->gPosition, e->gNormal, e->gAlbedoSpec};
    glDeleteTextures(3, textures);
    GLuint renderbuffers[3] = {e->rboDepth, e->screenColor, e->screenDepth};
    glDeleteRenderbuffers(3, renderbuffers);
    GLuint framebuffers[2] = {e->gBuffer, e->screen};
    glDeleteFramebuffers(2, framebuffers);
}

/* --- what the test checks ----------------------------------------------- */

/* The GL state around every call (capture, check_state). */
#include "tutorial_host_state.h"

static int check_status(DmsaaStatus status, const char *call)
{
    if (status != DMSAA_STATUS_OK) {
        fprintf(stderr, "FAIL: %s returned %d: %s\n", call, (int)status, dmsaa_last_error());
        failures++;
        return 0;
    }
    return 1;
}

static void check_gl_errors(const char *where)
{
    GLenum error = glGetError();
    CHECK(error == GL_NO_ERROR, "GL error 0x%04x after %s", error, where);
}

static void write_screen(const Engine *e, const char *dir, const char *name)
{
    size_t size = (size_t)e->width * (size_t)e->height * 4;
    unsigned char *pixels = malloc(size);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, e->screen);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, e->width, e->height, GL_RGBA, GL_UNSIGNED_BYTE, pixels);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    CHECK(f != NULL, "cannot write %s", path);
    if (f) {
        fwrite(pixels, 1, size, f);
        fclose(f);
    }
    free(pixels);
}

/* The 16x supersampled reference: the same frame at 4x the width and
 * height, each 4x4 block of the lit image averaged. */
/* An 8-bit sRGB value as linear light, and back (rounded). */
static double srgb_decode(unsigned char v)
{
    double c = v / 255.0;
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

static unsigned char srgb_encode(double l)
{
    double c = l <= 0.0031308 ? l * 12.92 : 1.055 * pow(l, 1.0 / 2.4) - 0.055;
    c = c < 0.0 ? 0.0 : c > 1.0 ? 1.0 : c;
    return (unsigned char)lround(c * 255.0);
}

static void write_reference(const char *dir)
{
    Engine big;
    engine_init(&big, SCR_WIDTH * SUPERSAMPLE, SCR_HEIGHT * SUPERSAMPLE);
    geometry_pass(&big, big.gBuffer);
    lighting_pass(&big);
    forward_pass(&big);
    size_t big_size = (size_t)big.width * (size_t)big.height * 4;
    unsigned char *pixels = malloc(big_size);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, big.screen);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, big.width, big.height, GL_RGBA, GL_UNSIGNED_BYTE, pixels);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    /* Averaged in the light a screen emits for the stored display values
     * (sRGB decoded, averaged, encoded again); alpha as stored. */
    unsigned char *small = malloc((size_t)SCR_WIDTH * SCR_HEIGHT * 4);
    for (int y = 0; y < SCR_HEIGHT; y++)
        for (int x = 0; x < SCR_WIDTH; x++)
            for (int c = 0; c < 4; c++) {
                double sum = 0.0;
                for (int dy = 0; dy < SUPERSAMPLE; dy++)
                    for (int dx = 0; dx < SUPERSAMPLE; dx++) {
                        unsigned char v = pixels[(((size_t)(y * SUPERSAMPLE + dy) * big.width) +
                                                  (size_t)(x * SUPERSAMPLE + dx)) * 4 + c];
                        sum += c == 3 ? v / 255.0 : srgb_decode(v);
                    }
                double mean = sum / (SUPERSAMPLE * SUPERSAMPLE);
                small[((size_t)y * SCR_WIDTH + x) * 4 + c] =
                    c == 3 ? (unsigned char)lround(mean * 255.0) : srgb_encode(mean);
            }
    char path[4096];
    snprintf(path, sizeof path, "%s/reference.rgba", dir);
    FILE *f = fopen(path, "wb");
    CHECK(f != NULL, "cannot write %s", path);
    if (f) {
        fwrite(small, 1, (size_t)SCR_WIDTH * SCR_HEIGHT * 4, f);
        fclose(f);
    }
    free(small);
    free(pixels);
    engine_free(&big);
}

/* The options this host gives: positions are world-space (the tutorial's
 * gPosition) and are the depth key; normals are gNormal, which the second
 * layer's clusters also split by. gNormal is selected (the reference
 * sample's normal) rather than blended: measured on this scene (FLIP
 * against the 16x image), one layer with blended normals (DMSAA_RULE_BLEND
 * or _BLEND_NORMAL) is further from it than no MSAA, and with selected
 * normals closer (docs/capi.md has the numbers). */
static DmsaaOptions tutorial_options(uint32_t layers)
{
    DmsaaOptions options = dmsaa_options_default();
    options.layers = layers;
    options.position_attachment = 0;
    options.world_space_position = 1;
    options.normal_attachment = 1;
    options.normal_encoding = DMSAA_NORMAL_XYZ;
    options.rules[1] = DMSAA_RULE_SELECT;
    /* its lighting writes display values (no tonemap): mixed in linear light */
    options.layer_mix = DMSAA_LAYER_MIX_SRGB_ENCODED;
    return options;
}

/* The pixels the selection stencil marks, read back through a framebuffer
 * of its own (the host reads, never writes, the library's texture); -1 when
 * a value is neither 0 nor DMSAA_SECOND_LAYER_SELECTED. */
static long count_selected(const Engine *e, GLuint selection)
{
    GLuint fbo = 0;
    glGenFramebuffers(1, &fbo);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo);
    glFramebufferTexture2D(GL_READ_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_TEXTURE_2D, selection, 0);
    glReadBuffer(GL_NONE);
    size_t n = (size_t)e->width * (size_t)e->height;
    unsigned char *stencil = malloc(n);
    long count = -1;
    if (stencil && glCheckFramebufferStatus(GL_READ_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE) {
        glPixelStorei(GL_PACK_ALIGNMENT, 1);
        glReadPixels(0, 0, e->width, e->height, GL_STENCIL_INDEX, GL_UNSIGNED_BYTE, stencil);
        glPixelStorei(GL_PACK_ALIGNMENT, 4);
        count = 0;
        for (size_t i = 0; i < n && count >= 0; i++) {
            if (stencil[i] == DMSAA_SECOND_LAYER_SELECTED)
                count++;
            else if (stencil[i] != 0)
                count = -1;
        }
    }
    free(stencil);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    glDeleteFramebuffers(1, &fbo);
    return count;
}

/* The second lighting where the host masks it with the library's selection
 * stencil: the selection stands in for the screen's depth attachment while
 * the unchanged lighting pass runs under an EQUAL stencil test that writes
 * nothing, then the screen gets its own depth back. */
static void masked_lighting_pass(Engine *e, GLuint selection)
{
    glBindFramebuffer(GL_FRAMEBUFFER, e->screen);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_TEXTURE_2D, selection, 0);
    glEnable(GL_STENCIL_TEST);
    glStencilFunc(GL_EQUAL, DMSAA_SECOND_LAYER_SELECTED, 0xFF);
    glStencilMask(0x00);
    lighting_pass(e);
    glStencilMask(0xFF);
    glDisable(GL_STENCIL_TEST);
    glBindFramebuffer(GL_FRAMEBUFFER, e->screen);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_TEXTURE_2D, 0, 0);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, e->screenDepth);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

/* One frame with the retrofit; two layers run the lighting twice, the
 * second time masked by the selection stencil when `masked`. */
static void retrofitted_frame(Engine *e, uint32_t layers, bool masked, const char *dir,
                              const char *name)
{
    GlState state;
    DmsaaOptions options = tutorial_options(layers);
    DmsaaRetrofit *msaa = NULL;
    /* the host's state at start-up, after its own set-up */
    glBindFramebuffer(GL_FRAMEBUFFER, e->gBuffer);
    glUseProgram(e->shaderGeometryPass);
    capture(e, &state);
    if (!check_status(dmsaa_retrofit_new(load_gl, NULL, e->gBuffer, &options, &msaa),
                      "dmsaa_retrofit_new"))
        return;
    check_state(e, &state, "dmsaa_retrofit_new");
    glBindFramebuffer(GL_FRAMEBUFFER, 0);

    uint32_t samples = 0;
    check_status(dmsaa_samples(msaa, &samples), "dmsaa_samples");
    printf("%s: %u samples, %u layer(s)\n", name, samples, layers);

    /* 1. the geometry pass, into the multisampled framebuffer */
    GLuint fbo = 0;
    check_status(dmsaa_begin_frame(msaa, &fbo), "dmsaa_begin_frame");
    geometry_pass(e, fbo);
    /* 2. the resolve, into the engine's own G-buffer */
    capture(e, &state);
    check_status(dmsaa_resolve(msaa, e->projection, e->view), "dmsaa_resolve");
    check_state(e, &state, "dmsaa_resolve");
    lighting_pass(e);
    if (layers == 2) {
        bool run_lighting = false;
        capture(e, &state);
        check_status(dmsaa_begin_second_layer(msaa, e->screen, &run_lighting),
                     "dmsaa_begin_second_layer");
        check_state(e, &state, "dmsaa_begin_second_layer");
        CHECK(run_lighting, "two layers, yet dmsaa_begin_second_layer asked for no second lighting");
        GLuint selection = 0;
        check_status(dmsaa_second_layer_selection(msaa, &selection), "dmsaa_second_layer_selection");
        CHECK(selection != 0 && glIsTexture(selection),
              "two layers, yet dmsaa_second_layer_selection gave no texture (%u)", selection);
        if (selection != 0) {
            long selected = count_selected(e, selection);
            printf("%s: %ld of %d pixels selected for the second layer\n", name, selected,
                   e->width * e->height);
            CHECK(selected > 0 && selected < (long)e->width * e->height,
                  "the selection stencil marks %ld of %d pixels", selected, e->width * e->height);
        }
        if (run_lighting) {
            if (masked && selection != 0)
                masked_lighting_pass(e, selection);
            else
                lighting_pass(e);
            capture(e, &state);
            check_status(dmsaa_finish_second_layer(msaa, e->screen), "dmsaa_finish_second_layer");
            check_state(e, &state, "dmsaa_finish_second_layer");
        }
    }
    /* 3. the light cubes through the forward target */
    GLuint forward = 0;
    capture(e, &state);
    check_status(dmsaa_begin_forward(msaa, e->screen, &forward), "dmsaa_begin_forward");
    check_state(e, &state, "dmsaa_begin_forward");
    CHECK(forward != 0 && glIsFramebuffer(forward), "dmsaa_begin_forward gave no framebuffer (%u)",
          forward);
    forward_pass_into(e, forward);
    capture(e, &state);
    check_status(dmsaa_finish_forward(msaa, e->screen), "dmsaa_finish_forward");
    check_state(e, &state, "dmsaa_finish_forward");
    check_gl_errors(name);
    write_screen(e, dir, name);

    CHECK(dmsaa_live_objects() > 0, "no live objects counted while the retrofit exists");
    capture(e, &state);
    dmsaa_destroy(msaa);
    check_state(e, &state, "dmsaa_destroy");
    CHECK(dmsaa_live_objects() == 0, "%lld GL objects of the library left after dmsaa_destroy",
          (long long)dmsaa_live_objects());
    CHECK(!glIsFramebuffer(fbo), "the multisampled framebuffer %u exists after dmsaa_destroy", fbo);
    /* the host's objects are the host's */
    CHECK(glIsFramebuffer(e->gBuffer) && glIsTexture(e->gPosition) && glIsTexture(e->gNormal) &&
              glIsTexture(e->gAlbedoSpec),
          "dmsaa_destroy freed a G-buffer object of the host's");
    check_gl_errors("dmsaa_destroy");
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: %s OUT_DIR\n", argv[0]);
        return 2;
    }
    const char *dir = argv[1];
    if (!create_context())
        return 3;
    GLint major = 0, minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    if (major * 10 + minor < 33)
        glsl_version_line = "#version 150 core\n#extension GL_ARB_explicit_attrib_location : require\n";
    printf("GL %s\n", (const char *)glGetString(GL_VERSION));

    Engine e;
    engine_init(&e, SCR_WIDTH, SCR_HEIGHT);
    printf("image %dx%d\n", SCR_WIDTH, SCR_HEIGHT);

    /* the engine as it is */
    geometry_pass(&e, e.gBuffer);
    lighting_pass(&e);
    forward_pass(&e);
    check_gl_errors("the frame without MSAA");
    write_screen(&e, dir, "none.rgba");

    retrofitted_frame(&e, 1, false, dir, "msaa.rgba");
    retrofitted_frame(&e, 2, false, dir, "layers.rgba");
    retrofitted_frame(&e, 2, true, dir, "layers-masked.rgba");

    /* the host still draws as before */
    geometry_pass(&e, e.gBuffer);
    lighting_pass(&e);
    forward_pass(&e);
    check_gl_errors("the frame after the retrofits");
    write_screen(&e, dir, "after.rgba");

    engine_free(&e);
    write_reference(dir);
    check_gl_errors("the supersampled frame");
    destroy_context();

    printf("state checks: %d library calls, GL state unchanged: %s\n", state_checks,
           failures == 0 ? "yes" : "no");
    printf("live objects after dmsaa_destroy: %lld\n", (long long)dmsaa_live_objects());
    if (failures) {
        fprintf(stderr, "%d check(s) failed\n", failures);
        return 1;
    }
    printf("ok\n");
    return 0;
}
