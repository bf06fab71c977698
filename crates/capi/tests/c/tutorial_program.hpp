// The LearnOpenGL "Deferred Shading" chapter's program, the parts every
// test program built from it shares (glfw_tutorial_host.cpp, retrofitted
// in its source; inject_tutorial.cpp, retrofitted in its source or by
// `deferred-msaa inject`): GL loaded through glfwGetProcAddress as a
// glad-generated loader does it, the chapter's shader class, shaders,
// cube and quad, the G-buffer and the passes. Nothing of the retrofit is
// here. glfw_tutorial_host.cpp's opening comment describes the program.
#ifndef TUTORIAL_PROGRAM_HPP
#define TUTORIAL_PROGRAM_HPP

// TUTORIAL_SDL: the window and the GL loader are SDL2's
// (SDL_GL_GetProcAddress); otherwise GLFW's (glfwGetProcAddress).
#ifdef TUTORIAL_SDL
#include <SDL2/SDL.h>
#define TUTORIAL_GET_PROC_ADDRESS(name) SDL_GL_GetProcAddress(name)
#else
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#define TUTORIAL_GET_PROC_ADDRESS(name) glfwGetProcAddress(name)
#endif
// TUTORIAL_LINK_GL: the program calls libGL's symbols directly (linked
// with -lGL), as a program that loads nothing at run time does.
#ifdef TUTORIAL_LINK_GL
#define GL_GLEXT_PROTOTYPES
#endif
#include <GL/glcorearb.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

// ---------------------------------------------------------------------------
// The loader: every GL function the program calls, through
// glfwGetProcAddress, as a glad-generated loader fills its pointers.
#define GL_FUNCTIONS(X)                                                                    \
    X(PFNGLACTIVETEXTUREPROC, glActiveTexture)                                             \
    X(PFNGLATTACHSHADERPROC, glAttachShader)                                               \
    X(PFNGLBINDBUFFERPROC, glBindBuffer)                                                   \
    X(PFNGLBINDFRAMEBUFFERPROC, glBindFramebuffer)                                         \
    X(PFNGLBINDRENDERBUFFERPROC, glBindRenderbuffer)                                       \
    X(PFNGLBINDTEXTUREPROC, glBindTexture)                                                 \
    X(PFNGLBLENDFUNCPROC, glBlendFunc)                                                     \
    X(PFNGLBINDVERTEXARRAYPROC, glBindVertexArray)                                         \
    X(PFNGLBLITFRAMEBUFFERPROC, glBlitFramebuffer)                                         \
    X(PFNGLBUFFERDATAPROC, glBufferData)                                                   \
    X(PFNGLCHECKFRAMEBUFFERSTATUSPROC, glCheckFramebufferStatus)                           \
    X(PFNGLCLEARPROC, glClear)                                                             \
    X(PFNGLCLEARCOLORPROC, glClearColor)                                                   \
    X(PFNGLCOMPILESHADERPROC, glCompileShader)                                             \
    X(PFNGLCREATEPROGRAMPROC, glCreateProgram)                                             \
    X(PFNGLCREATESHADERPROC, glCreateShader)                                               \
    X(PFNGLDELETEBUFFERSPROC, glDeleteBuffers)                                             \
    X(PFNGLDELETEFRAMEBUFFERSPROC, glDeleteFramebuffers)                                   \
    X(PFNGLDELETEPROGRAMPROC, glDeleteProgram)                                             \
    X(PFNGLDELETERENDERBUFFERSPROC, glDeleteRenderbuffers)                                 \
    X(PFNGLDELETESHADERPROC, glDeleteShader)                                               \
    X(PFNGLDELETETEXTURESPROC, glDeleteTextures)                                           \
    X(PFNGLDELETEVERTEXARRAYSPROC, glDeleteVertexArrays)                                   \
    X(PFNGLDEPTHMASKPROC, glDepthMask)                                                     \
    X(PFNGLDISABLEPROC, glDisable)                                                         \
    X(PFNGLDRAWARRAYSPROC, glDrawArrays)                                                   \
    X(PFNGLDRAWBUFFERSPROC, glDrawBuffers)                                                 \
    X(PFNGLENABLEPROC, glEnable)                                                           \
    X(PFNGLENABLEVERTEXATTRIBARRAYPROC, glEnableVertexAttribArray)                         \
    X(PFNGLFRAMEBUFFERRENDERBUFFERPROC, glFramebufferRenderbuffer)                         \
    X(PFNGLFRAMEBUFFERTEXTURE2DPROC, glFramebufferTexture2D)                               \
    X(PFNGLGENBUFFERSPROC, glGenBuffers)                                                   \
    X(PFNGLGENFRAMEBUFFERSPROC, glGenFramebuffers)                                         \
    X(PFNGLGENRENDERBUFFERSPROC, glGenRenderbuffers)                                       \
    X(PFNGLGENTEXTURESPROC, glGenTextures)                                                 \
    X(PFNGLGENVERTEXARRAYSPROC, glGenVertexArrays)                                         \
    X(PFNGLGETERRORPROC, glGetError)                                                       \
    X(PFNGLGETFRAMEBUFFERATTACHMENTPARAMETERIVPROC, glGetFramebufferAttachmentParameteriv) \
    X(PFNGLGETINTEGERVPROC, glGetIntegerv)                                                 \
    X(PFNGLGETPROGRAMINFOLOGPROC, glGetProgramInfoLog)                                     \
    X(PFNGLGETPROGRAMIVPROC, glGetProgramiv)                                               \
    X(PFNGLGETSHADERINFOLOGPROC, glGetShaderInfoLog)                                       \
    X(PFNGLGETSHADERIVPROC, glGetShaderiv)                                                 \
    X(PFNGLGETSTRINGPROC, glGetString)                                                     \
    X(PFNGLGETUNIFORMLOCATIONPROC, glGetUniformLocation)                                   \
    X(PFNGLISENABLEDPROC, glIsEnabled)                                                     \
    X(PFNGLLINKPROGRAMPROC, glLinkProgram)                                                 \
    X(PFNGLPIXELSTOREIPROC, glPixelStorei)                                                 \
    X(PFNGLREADBUFFERPROC, glReadBuffer)                                                   \
    X(PFNGLREADPIXELSPROC, glReadPixels)                                                   \
    X(PFNGLRENDERBUFFERSTORAGEPROC, glRenderbufferStorage)                                 \
    X(PFNGLSHADERSOURCEPROC, glShaderSource)                                               \
    X(PFNGLSTENCILFUNCPROC, glStencilFunc)                                                 \
    X(PFNGLSTENCILMASKPROC, glStencilMask)                                                 \
    X(PFNGLTEXIMAGE2DPROC, glTexImage2D)                                                   \
    X(PFNGLTEXPARAMETERIPROC, glTexParameteri)                                             \
    X(PFNGLUNIFORM1FPROC, glUniform1f)                                                     \
    X(PFNGLUNIFORM1IPROC, glUniform1i)                                                     \
    X(PFNGLUNIFORM3FPROC, glUniform3f)                                                     \
    X(PFNGLUNIFORMMATRIX4FVPROC, glUniformMatrix4fv)                                       \
    X(PFNGLUSEPROGRAMPROC, glUseProgram)                                                   \
    X(PFNGLVERTEXATTRIBPOINTERPROC, glVertexAttribPointer)                                 \
    X(PFNGLVIEWPORTPROC, glViewport)

#ifdef TUTORIAL_LINK_GL
static inline bool loadGL() { return true; }
#else
#define DECLARE(type, name) static type name;
GL_FUNCTIONS(DECLARE)
#undef DECLARE

static inline bool loadGL()
{
    bool ok = true;
#define LOAD(type, name)                                                  \
    name = reinterpret_cast<type>(TUTORIAL_GET_PROC_ADDRESS(#name));      \
    if (!name) {                                                          \
        std::fprintf(stderr, "glfw_tutorial_host: no %s\n", #name);       \
        ok = false;                                                       \
    }
    GL_FUNCTIONS(LOAD)
#undef LOAD
    return ok;
}
#endif


// ---------------------------------------------------------------------------
static int failures = 0;
#define CHECK(cond, ...)                                             \
    do {                                                             \
        if (!(cond)) {                                               \
            std::fprintf(stderr, "check failed: " __VA_ARGS__);      \
            std::fprintf(stderr, "\n");                              \
            failures++;                                              \
        }                                                            \
    } while (0)

static inline void checkGlErrors(const char *where)
{
    for (GLenum e = glGetError(); e != GL_NO_ERROR; e = glGetError()) {
        std::fprintf(stderr, "GL error 0x%04x after %s\n", e, where);
        failures++;
    }
}

// ---------------------------------------------------------------------------
// Small matrix helpers in place of glm (column-major, as GL takes them).
struct Mat4 {
    std::array<float, 16> m{};
    static Mat4 identity()
    {
        Mat4 r;
        r.m[0] = r.m[5] = r.m[10] = r.m[15] = 1.0f;
        return r;
    }
    Mat4 operator*(const Mat4 &o) const
    {
        Mat4 r;
        for (int c = 0; c < 4; c++)
            for (int row = 0; row < 4; row++) {
                float s = 0.0f;
                for (int k = 0; k < 4; k++)
                    s += m[k * 4 + row] * o.m[c * 4 + k];
                r.m[c * 4 + row] = s;
            }
        return r;
    }
};

static inline Mat4 perspective(float fovy, float aspect, float zNear, float zFar)
{
    Mat4 r;
    float f = 1.0f / std::tan(fovy / 2.0f);
    r.m[0] = f / aspect;
    r.m[5] = f;
    r.m[10] = (zFar + zNear) / (zNear - zFar);
    r.m[11] = -1.0f;
    r.m[14] = 2.0f * zFar * zNear / (zNear - zFar);
    return r;
}

struct Vec3 {
    float x, y, z;
};

static inline Vec3 sub(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
static inline Vec3 cross(Vec3 a, Vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
static inline Vec3 normalize(Vec3 v)
{
    float l = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
    return {v.x / l, v.y / l, v.z / l};
}
static inline float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

static inline Mat4 lookAt(Vec3 eye, Vec3 center, Vec3 up)
{
    Vec3 f = normalize(sub(center, eye));
    Vec3 s = normalize(cross(f, up));
    Vec3 u = cross(s, f);
    Mat4 r = Mat4::identity();
    r.m[0] = s.x; r.m[4] = s.y; r.m[8] = s.z;
    r.m[1] = u.x; r.m[5] = u.y; r.m[9] = u.z;
    r.m[2] = -f.x; r.m[6] = -f.y; r.m[10] = -f.z;
    r.m[12] = -dot(s, eye);
    r.m[13] = -dot(u, eye);
    r.m[14] = dot(f, eye);
    return r;
}

static inline Mat4 translate(Vec3 t)
{
    Mat4 r = Mat4::identity();
    r.m[12] = t.x; r.m[13] = t.y; r.m[14] = t.z;
    return r;
}

static inline Mat4 scale(float s)
{
    Mat4 r = Mat4::identity();
    r.m[0] = r.m[5] = r.m[10] = s;
    return r;
}

static inline Mat4 rotate(float angle, Vec3 axis)
{
    Vec3 a = normalize(axis);
    float c = std::cos(angle), s = std::sin(angle), t = 1.0f - c;
    Mat4 r = Mat4::identity();
    r.m[0] = t * a.x * a.x + c;       r.m[4] = t * a.x * a.y - s * a.z; r.m[8] = t * a.x * a.z + s * a.y;
    r.m[1] = t * a.x * a.y + s * a.z; r.m[5] = t * a.y * a.y + c;       r.m[9] = t * a.y * a.z - s * a.x;
    r.m[2] = t * a.x * a.z - s * a.y; r.m[6] = t * a.y * a.z + s * a.x; r.m[10] = t * a.z * a.z + c;
    return r;
}

// ---------------------------------------------------------------------------
// The chapter's shader class, cut down to what the program uses.
static std::string glslVersion = "#version 330 core\n";

class Shader {
public:
    GLuint ID = 0;
    Shader(const char *vertexCode, const char *fragmentCode)
    {
        GLuint vertex = compile(GL_VERTEX_SHADER, vertexCode);
        GLuint fragment = compile(GL_FRAGMENT_SHADER, fragmentCode);
        ID = glCreateProgram();
        glAttachShader(ID, vertex);
        glAttachShader(ID, fragment);
        glLinkProgram(ID);
        GLint success = 0;
        glGetProgramiv(ID, GL_LINK_STATUS, &success);
        if (!success) {
            char log[1024];
            glGetProgramInfoLog(ID, sizeof log, nullptr, log);
            std::fprintf(stderr, "ERROR::PROGRAM_LINKING_ERROR\n%s\n", log);
            failures++;
        }
        glDeleteShader(vertex);
        glDeleteShader(fragment);
    }
    void use() const { glUseProgram(ID); }
    void setInt(const char *name, int value) const { glUniform1i(glGetUniformLocation(ID, name), value); }
    void setFloat(const char *name, float value) const { glUniform1f(glGetUniformLocation(ID, name), value); }
    void setVec3(const char *name, Vec3 v) const { glUniform3f(glGetUniformLocation(ID, name), v.x, v.y, v.z); }
    void setMat4(const char *name, const Mat4 &mat) const
    {
        glUniformMatrix4fv(glGetUniformLocation(ID, name), 1, GL_FALSE, mat.m.data());
    }

private:
    static GLuint compile(GLenum type, const char *code)
    {
        GLuint shader = glCreateShader(type);
        // On a 3.2 context (the CI's floor) the 3.30 text compiles as 1.50
        // with the extension that gives it layout locations.
        const char *sources[2] = {glslVersion.c_str(), code};
        glShaderSource(shader, 2, sources, nullptr);
        glCompileShader(shader);
        GLint success = 0;
        glGetShaderiv(shader, GL_COMPILE_STATUS, &success);
        if (!success) {
            char log[1024];
            glGetShaderInfoLog(shader, sizeof log, nullptr, log);
            std::fprintf(stderr, "ERROR::SHADER_COMPILATION_ERROR\n%s\n", log);
            failures++;
        }
        return shader;
    }
};

static const char *gBufferVs = R"(
layout (location = 0) in vec3 aPos;
layout (location = 1) in vec3 aNormal;
layout (location = 2) in vec2 aTexCoords;
out vec3 FragPos;
out vec2 TexCoords;
out vec3 Normal;
uniform mat4 model;
uniform mat4 view;
uniform mat4 projection;
void main()
{
    vec4 worldPos = model * vec4(aPos, 1.0);
    FragPos = worldPos.xyz;
    TexCoords = aTexCoords;
    Normal = mat3(transpose(inverse(model))) * aNormal;
    gl_Position = projection * view * worldPos;
}
)";

static const char *gBufferFs = R"(
layout (location = 0) out vec3 gPosition;
layout (location = 1) out vec3 gNormal;
layout (location = 2) out vec4 gAlbedoSpec;
in vec2 TexCoords;
in vec3 FragPos;
in vec3 Normal;
uniform vec3 diffuseColor;
uniform float specularIntensity;
void main()
{
    gPosition = FragPos;
    gNormal = normalize(Normal);
    gAlbedoSpec.rgb = diffuseColor;
    gAlbedoSpec.a = specularIntensity;
}
)";

static const char *quadVs = R"(
layout (location = 0) in vec3 aPos;
layout (location = 1) in vec2 aTexCoords;
out vec2 TexCoords;
void main()
{
    TexCoords = aTexCoords;
    gl_Position = vec4(aPos, 1.0);
}
)";

// The chapter's lighting: Blinn-Phong over 32 attenuated point lights. In
// the gamma-correct variant (SRGB_OUTPUT) the albedo is decoded first and
// GL encodes the output; the chapter's own writes its sums as they are.
static const char *lightingFs = R"(
out vec4 FragColor;
in vec2 TexCoords;
uniform sampler2D gPosition;
uniform sampler2D gNormal;
uniform sampler2D gAlbedoSpec;
struct Light {
    vec3 Position;
    vec3 Color;
    float Linear;
    float Quadratic;
};
const int NR_LIGHTS = 32;
uniform Light lights[NR_LIGHTS];
uniform vec3 viewPos;
uniform int linearAlbedo;
void main()
{
    vec3 FragPos = texture(gPosition, TexCoords).rgb;
    vec3 Normal = texture(gNormal, TexCoords).rgb;
    vec3 Diffuse = texture(gAlbedoSpec, TexCoords).rgb;
    if (linearAlbedo == 1)
        Diffuse = pow(Diffuse, vec3(2.2));
    float Specular = texture(gAlbedoSpec, TexCoords).a;
    vec3 lighting = Diffuse * 0.1;
    vec3 viewDir = normalize(viewPos - FragPos);
    for (int i = 0; i < NR_LIGHTS; ++i)
    {
        vec3 lightDir = normalize(lights[i].Position - FragPos);
        vec3 diffuse = max(dot(Normal, lightDir), 0.0) * Diffuse * lights[i].Color;
        vec3 halfwayDir = normalize(lightDir + viewDir);
        float spec = pow(max(dot(Normal, halfwayDir), 0.0), 16.0);
        vec3 specular = lights[i].Color * spec * Specular;
        float distance = length(lights[i].Position - FragPos);
        float attenuation = 1.0 / (1.0 + lights[i].Linear * distance + lights[i].Quadratic * distance * distance);
        diffuse *= attenuation;
        specular *= attenuation;
        lighting += diffuse + specular;
    }
    FragColor = vec4(lighting, 1.0);
}
)";

static const char *lightBoxVs = R"(
layout (location = 0) in vec3 aPos;
layout (location = 1) in vec3 aNormal;
layout (location = 2) in vec2 aTexCoords;
uniform mat4 projection;
uniform mat4 view;
uniform mat4 model;
void main()
{
    gl_Position = projection * view * model * vec4(aPos, 1.0);
}
)";

static const char *lightBoxFs = R"(
layout (location = 0) out vec4 FragColor;
uniform vec3 lightColor;
void main()
{
    FragColor = vec4(lightColor, 1.0);
}
)";

// ---------------------------------------------------------------------------
static const int SCR_WIDTH = 320;
static const int SCR_HEIGHT = 180;
static const int SUPERSAMPLE = 4;
static const int NR_LIGHTS = 32;

static const Vec3 cameraPosition = {0.0f, 5.5f, 5.5f};
static const Vec3 cameraTarget = {0.0f, -0.5f, -0.3f};

static GLuint cubeVAO = 0, cubeVBO = 0;
static inline void renderCube()
{
    if (cubeVAO == 0) {
        // position, normal, texture coordinates: 6 faces of 2 triangles
        static const float faces[6][3][3] = {
            // normal, then the two axes spanning the face
            {{0, 0, -1}, {-1, 0, 0}, {0, 1, 0}}, {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},
            {{-1, 0, 0}, {0, 0, 1}, {0, 1, 0}},  {{1, 0, 0}, {0, 0, -1}, {0, 1, 0}},
            {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}},  {{0, 1, 0}, {1, 0, 0}, {0, 0, -1}},
        };
        static const float corners[6][2] = {{-1, -1}, {1, -1}, {1, 1}, {1, 1}, {-1, 1}, {-1, -1}};
        std::vector<float> vertices;
        for (const auto &f : faces)
            for (const auto &c : corners) {
                for (int k = 0; k < 3; k++)
                    vertices.push_back(f[0][k] + c[0] * f[1][k] + c[1] * f[2][k]);
                for (int k = 0; k < 3; k++)
                    vertices.push_back(f[0][k]);
                vertices.push_back(c[0] * 0.5f + 0.5f);
                vertices.push_back(c[1] * 0.5f + 0.5f);
            }
        glGenVertexArrays(1, &cubeVAO);
        glGenBuffers(1, &cubeVBO);
        glBindBuffer(GL_ARRAY_BUFFER, cubeVBO);
        glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(float)),
                     vertices.data(), GL_STATIC_DRAW);
        glBindVertexArray(cubeVAO);
        glEnableVertexAttribArray(0);
        glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 8 * sizeof(float), (void *)0);
        glEnableVertexAttribArray(1);
        glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 8 * sizeof(float), (void *)(3 * sizeof(float)));
        glEnableVertexAttribArray(2);
        glVertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, 8 * sizeof(float), (void *)(6 * sizeof(float)));
        glBindBuffer(GL_ARRAY_BUFFER, 0);
        glBindVertexArray(0);
    }
    glBindVertexArray(cubeVAO);
    glDrawArrays(GL_TRIANGLES, 0, 36);
    glBindVertexArray(0);
}

static GLuint quadVAO = 0, quadVBO = 0;
static inline void renderQuad()
{
    if (quadVAO == 0) {
        float quadVertices[] = {
            -1.0f, 1.0f, 0.0f, 0.0f, 1.0f, -1.0f, -1.0f, 0.0f, 0.0f, 0.0f,
            1.0f,  1.0f, 0.0f, 1.0f, 1.0f, 1.0f,  -1.0f, 0.0f, 1.0f, 0.0f,
        };
        glGenVertexArrays(1, &quadVAO);
        glGenBuffers(1, &quadVBO);
        glBindVertexArray(quadVAO);
        glBindBuffer(GL_ARRAY_BUFFER, quadVBO);
        glBufferData(GL_ARRAY_BUFFER, sizeof(quadVertices), &quadVertices, GL_STATIC_DRAW);
        glEnableVertexAttribArray(0);
        glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 5 * sizeof(float), (void *)0);
        glEnableVertexAttribArray(1);
        glVertexAttribPointer(1, 2, GL_FLOAT, GL_FALSE, 5 * sizeof(float), (void *)(3 * sizeof(float)));
    }
    glBindVertexArray(quadVAO);
    glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
    glBindVertexArray(0);
}

// ---------------------------------------------------------------------------
struct Engine {
    int width = 0, height = 0;
    GLuint gBuffer = 0, gPosition = 0, gNormal = 0, gAlbedoSpec = 0, rboDepth = 0;
    Shader *shaderGeometryPass = nullptr, *shaderLightingPass = nullptr, *shaderLightBox = nullptr;
    std::vector<Vec3> objectPositions, lightPositions, lightColors;
    Mat4 projection, view;
    bool gammaCorrect = false;
};

static inline GLuint makeTexture(int w, int h, GLint internal, GLenum type)
{
    GLuint t;
    glGenTextures(1, &t);
    glBindTexture(GL_TEXTURE_2D, t);
    glTexImage2D(GL_TEXTURE_2D, 0, internal, w, h, 0, GL_RGBA, type, NULL);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    return t;
}

static inline void engineInit(Engine &e, int width, int height, bool gammaCorrect)
{
    e.width = width;
    e.height = height;
    e.gammaCorrect = gammaCorrect;
    glEnable(GL_DEPTH_TEST);
    e.shaderGeometryPass = new Shader(gBufferVs, gBufferFs);
    e.shaderLightingPass = new Shader(quadVs, lightingFs);
    e.shaderLightBox = new Shader(lightBoxVs, lightBoxFs);
    for (int z = -1; z <= 1; z++)
        for (int x = -1; x <= 1; x++)
            e.objectPositions.push_back({3.0f * static_cast<float>(x), -0.5f, 3.0f * static_cast<float>(z)});

    // configure g-buffer framebuffer
    glGenFramebuffers(1, &e.gBuffer);
    glBindFramebuffer(GL_FRAMEBUFFER, e.gBuffer);
    e.gPosition = makeTexture(width, height, GL_RGBA16F, GL_FLOAT);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, e.gPosition, 0);
    e.gNormal = makeTexture(width, height, GL_RGBA16F, GL_FLOAT);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D, e.gNormal, 0);
    e.gAlbedoSpec = makeTexture(width, height, GL_RGBA, GL_UNSIGNED_BYTE);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT2, GL_TEXTURE_2D, e.gAlbedoSpec, 0);
    unsigned int attachments[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
    glDrawBuffers(3, attachments);
    glGenRenderbuffers(1, &e.rboDepth);
    glBindRenderbuffer(GL_RENDERBUFFER, e.rboDepth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT, width, height);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, e.rboDepth);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) {
        std::fprintf(stderr, "Framebuffer not complete!\n");
        failures++;
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);

    // lighting info
    std::srand(13);
    for (int i = 0; i < NR_LIGHTS; i++) {
        float xPos = static_cast<float>(((std::rand() % 100) / 100.0) * 6.0 - 3.0);
        float yPos = static_cast<float>(((std::rand() % 100) / 100.0) * 6.0 - 4.0);
        float zPos = static_cast<float>(((std::rand() % 100) / 100.0) * 6.0 - 3.0);
        e.lightPositions.push_back({xPos, yPos + 2.0f, zPos});
        float rColor = static_cast<float>(((std::rand() % 100) / 200.0f) + 0.5);
        float gColor = static_cast<float>(((std::rand() % 100) / 200.0f) + 0.5);
        float bColor = static_cast<float>(((std::rand() % 100) / 200.0f) + 0.5);
        e.lightColors.push_back({rColor, gColor, bColor});
    }

    // shader configuration
    e.shaderLightingPass->use();
    e.shaderLightingPass->setInt("gPosition", 0);
    e.shaderLightingPass->setInt("gNormal", 1);
    e.shaderLightingPass->setInt("gAlbedoSpec", 2);
    e.shaderLightingPass->setInt("linearAlbedo", gammaCorrect ? 1 : 0);

    e.projection = perspective(45.0f * 3.14159265f / 180.0f, static_cast<float>(width) / static_cast<float>(height),
                               0.1f, 100.0f);
    e.view = lookAt(cameraPosition, cameraTarget, {0.0f, 1.0f, 0.0f});
}

static inline void engineFree(Engine &e)
{
    glDeleteFramebuffers(1, &e.gBuffer);
    GLuint textures[3] = {e.gPosition, e.gNormal, e.gAlbedoSpec};
    glDeleteTextures(3, textures);
    glDeleteRenderbuffers(1, &e.rboDepth);
    for (Shader *s : {e.shaderGeometryPass, e.shaderLightingPass, e.shaderLightBox}) {
        glDeleteProgram(s->ID);
        delete s;
    }
}

// 1. geometry pass: render scene's geometry/color data into gbuffer
// (`target`: the G-buffer, or the retrofit's framebuffer in its place)
static inline void geometryPass(Engine &e, GLuint target)
{
    glBindFramebuffer(GL_FRAMEBUFFER, target);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    e.shaderGeometryPass->use();
    e.shaderGeometryPass->setMat4("projection", e.projection);
    e.shaderGeometryPass->setMat4("view", e.view);
    for (size_t i = 0; i < e.objectPositions.size(); i++) {
        float fi = static_cast<float>(i);
        Mat4 model = translate(e.objectPositions[i]) * rotate(0.35f + 0.6f * fi, {1.0f, 0.8f, 0.3f}) * scale(0.6f);
        e.shaderGeometryPass->setMat4("model", model);
        e.shaderGeometryPass->setVec3("diffuseColor",
                                      {0.45f + 0.06f * fi, 0.85f - 0.05f * fi, 0.5f + 0.04f * static_cast<float>(i % 3)});
        e.shaderGeometryPass->setFloat("specularIntensity", 0.25f + 0.08f * fi);
        renderCube();
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

// 2. lighting pass: calculate lighting by iterating over a screen filled
// quad pixel-by-pixel using the gbuffer's content (the draw alone; the
// frame binds its target and clears it first, as the chapter's loop does)
static inline void lightingQuad(Engine &e)
{
    e.shaderLightingPass->use();
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, e.gPosition);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, e.gNormal);
    glActiveTexture(GL_TEXTURE2);
    glBindTexture(GL_TEXTURE_2D, e.gAlbedoSpec);
    char name[64];
    for (int i = 0; i < NR_LIGHTS; i++) {
        std::snprintf(name, sizeof name, "lights[%d].Position", i);
        e.shaderLightingPass->setVec3(name, e.lightPositions[static_cast<size_t>(i)]);
        std::snprintf(name, sizeof name, "lights[%d].Color", i);
        e.shaderLightingPass->setVec3(name, e.lightColors[static_cast<size_t>(i)]);
        const float linear = 0.7f;
        const float quadratic = 1.8f;
        std::snprintf(name, sizeof name, "lights[%d].Linear", i);
        e.shaderLightingPass->setFloat(name, linear);
        std::snprintf(name, sizeof name, "lights[%d].Quadratic", i);
        e.shaderLightingPass->setFloat(name, quadratic);
    }
    e.shaderLightingPass->setVec3("viewPos", cameraPosition);
    renderQuad();
}

// 2.5. copy content of geometry's depth buffer to the screen's depth buffer
static inline void blitDepth(Engine &e, GLuint screen)
{
    glBindFramebuffer(GL_READ_FRAMEBUFFER, e.gBuffer);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, screen);
    glBlitFramebuffer(0, 0, e.width, e.height, 0, 0, e.width, e.height, GL_DEPTH_BUFFER_BIT, GL_NEAREST);
    glBindFramebuffer(GL_FRAMEBUFFER, screen);
}

// 3. render lights on top of scene (into whatever framebuffer is bound)
static inline void lightCubes(Engine &e)
{
    e.shaderLightBox->use();
    e.shaderLightBox->setMat4("projection", e.projection);
    e.shaderLightBox->setMat4("view", e.view);
    for (size_t i = 0; i < e.lightPositions.size(); i++) {
        Mat4 model = translate(e.lightPositions[i]) * scale(0.125f);
        e.shaderLightBox->setMat4("model", model);
        Vec3 c = e.lightColors[i];
        if (e.gammaCorrect)
            c = {std::pow(c.x, 2.2f), std::pow(c.y, 2.2f), std::pow(c.z, 2.2f)};
        e.shaderLightBox->setVec3("lightColor", c);
        renderCube();
    }
}

// A framebuffer of the host's with one colour texture and a depth
// renderbuffer, for the lighting (or for the supersampled frame).
struct Screen {
    GLuint fbo = 0, color = 0, depth = 0;
};

static inline Screen makeScreen(int w, int h, GLint internal)
{
    Screen s;
    glGenFramebuffers(1, &s.fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, s.fbo);
    s.color = makeTexture(w, h, internal, GL_UNSIGNED_BYTE);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, s.color, 0);
    glGenRenderbuffers(1, &s.depth);
    glBindRenderbuffer(GL_RENDERBUFFER, s.depth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, w, h);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, s.depth);
    CHECK(glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE, "screen FBO incomplete");
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    return s;
}

static inline void freeScreen(Screen &s)
{
    glDeleteFramebuffers(1, &s.fbo);
    glDeleteTextures(1, &s.color);
    glDeleteRenderbuffers(1, &s.depth);
}

static inline double decode(unsigned char v)
{
    double c = v / 255.0;
    return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

static inline unsigned char encode(double l)
{
    double c = l <= 0.0031308 ? l * 12.92 : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055;
    return static_cast<unsigned char>(std::lround(std::fmin(std::fmax(c, 0.0), 1.0) * 255.0));
}

// The program's own 16x image at `width` x `height`: every pass at 4x the
// width and height into a framebuffer of its own (as the lit target and
// the screen), averaged 4x4 in the light a screen emits; rows bottom-up.
// The viewport is left at `width` x `height`.
static inline std::vector<unsigned char> supersampled(int width, int height, bool gammaCorrect)
{
    Engine big;
    int w = width * SUPERSAMPLE, h = height * SUPERSAMPLE;
    engineInit(big, w, h, gammaCorrect);
    Screen screen = makeScreen(w, h, gammaCorrect ? GL_SRGB8_ALPHA8 : GL_RGBA8);
    glViewport(0, 0, w, h);
    glBindFramebuffer(GL_FRAMEBUFFER, screen.fbo);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    if (gammaCorrect)
        glEnable(GL_FRAMEBUFFER_SRGB);
    geometryPass(big, big.gBuffer);
    glBindFramebuffer(GL_FRAMEBUFFER, screen.fbo);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    lightingQuad(big);
    blitDepth(big, screen.fbo);
    lightCubes(big);
    glDisable(GL_FRAMEBUFFER_SRGB);
    std::vector<unsigned char> pixels(static_cast<size_t>(w) * static_cast<size_t>(h) * 4);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, screen.fbo);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, pixels.data());
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, width, height);
    freeScreen(screen);
    engineFree(big);
    std::vector<unsigned char> small(static_cast<size_t>(width) * static_cast<size_t>(height) * 4);
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++)
            for (int c = 0; c < 4; c++) {
                double sum = 0.0;
                for (int dy = 0; dy < SUPERSAMPLE; dy++)
                    for (int dx = 0; dx < SUPERSAMPLE; dx++) {
                        size_t i = ((static_cast<size_t>(y * SUPERSAMPLE + dy) * static_cast<size_t>(w)) +
                                    static_cast<size_t>(x * SUPERSAMPLE + dx)) * 4 + static_cast<size_t>(c);
                        sum += c == 3 ? pixels[i] / 255.0 : decode(pixels[i]);
                    }
                double mean = sum / (SUPERSAMPLE * SUPERSAMPLE);
                small[(static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)) * 4 +
                      static_cast<size_t>(c)] =
                    c == 3 ? static_cast<unsigned char>(std::lround(mean * 255.0)) : encode(mean);
            }
    return small;
}

// The edge pixels of the engine's last frame, from its G-buffer (one byte a
// pixel, 255 on an edge, rows bottom-up): a 4-neighbour that is background
// where this pixel is geometry (or the reverse), whose position is more
// than 2% of this pixel's distance to the camera away, or whose normal
// turns more than 10 degrees.
static inline std::vector<unsigned char> edgeMask(Engine &e)
{
    const int w = e.width, h = e.height;
    std::vector<float> position(static_cast<size_t>(w) * static_cast<size_t>(h) * 4);
    std::vector<float> normal(position.size());
    glBindFramebuffer(GL_READ_FRAMEBUFFER, e.gBuffer);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glReadPixels(0, 0, w, h, GL_RGBA, GL_FLOAT, position.data());
    glReadBuffer(GL_COLOR_ATTACHMENT1);
    glReadPixels(0, 0, w, h, GL_RGBA, GL_FLOAT, normal.data());
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    auto at = [&](const std::vector<float> &v, int i) { return Vec3{v[4 * i], v[4 * i + 1], v[4 * i + 2]}; };
    auto length = [](Vec3 v) { return std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z); };
    std::vector<unsigned char> mask(static_cast<size_t>(w) * static_cast<size_t>(h), 0);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            int i = y * w + x;
            Vec3 p = at(position, i), n = at(normal, i);
            bool geometry = length(n) > 0.5f;
            static const int d[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
            for (const auto &step : d) {
                int nx = x + step[0], ny = y + step[1];
                if (nx < 0 || ny < 0 || nx >= w || ny >= h)
                    continue;
                int j = ny * w + nx;
                Vec3 q = at(position, j), m = at(normal, j);
                bool other = length(m) > 0.5f;
                bool edge = geometry != other;
                if (geometry && other) {
                    Vec3 toCamera = {p.x - cameraPosition.x, p.y - cameraPosition.y, p.z - cameraPosition.z};
                    Vec3 apart = {p.x - q.x, p.y - q.y, p.z - q.z};
                    float turn = (n.x * m.x + n.y * m.y + n.z * m.z) / (length(n) * length(m));
                    edge = length(apart) > 0.02f * length(toCamera) || turn < 0.985f;
                }
                if (edge)
                    mask[static_cast<size_t>(i)] = 255;
            }
        }
    return mask;
}

#endif
