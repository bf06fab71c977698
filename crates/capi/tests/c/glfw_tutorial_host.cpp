// A C++ host written the way the LearnOpenGL "Deferred Shading" chapter's
// program is: a GLFW window, GL loaded through glfwGetProcAddress (as glad
// does it: function pointers filled at start-up), GL_DEPTH_TEST enabled
// once at start-up and left on for the whole frame, the G-buffer
// (gPosition and gNormal RGBA16F, gAlbedoSpec unsized GL_RGBA, a
// GL_DEPTH_COMPONENT renderbuffer), the lighting pass drawn as a screen
// quad straight into the window's framebuffer 0 after its own glClear of
// colour and depth, the G-buffer's depth blitted to framebuffer 0, and the
// lights drawn forward as small cubes. The window asks for an
// sRGB-capable framebuffer (GLFW_SRGB_CAPABLE), which Mesa gives it, and
// never enables GL_FRAMEBUFFER_SRGB, as the chapter does not.
//
// Departures, each for the test's sake: cubes instead of the backpack
// model, the camera looking down on the 3x3 grid, one frame drawn per
// variant and read back from the back buffer before the swap, and a
// gamma-correct variant (GL_FRAMEBUFFER_SRGB on while drawing, linear
// values out of the shaders) beside the chapter's own.
//
// The retrofit as a new user adds it from docs/capi.md: the G-buffer
// bound through dmsaa_framebuffer and dmsaa_resolve after the geometry
// pass (one layer); dmsaa_begin_second_layer_own_target, the lighting
// quad again into the framebuffer it gives (stencil-tested on the
// selection), dmsaa_finish_second_layer (two layers); and the light cubes
// drawn into dmsaa_begin_forward's framebuffer, then
// dmsaa_finish_forward (the forward target).
//
// It writes raw RGBA8 images (rows bottom-up) into OUT_DIR:
//   none.rgba            the chapter's frame, no MSAA
//   msaa.rgba            one layer
//   layers.rgba          two layers, lit into framebuffer 0
//   layers-forward.rgba  two layers and the forward target
//   forward.rgba         one layer and the forward target
//   layers-fbo.rgba      two layers, the lighting into an RGBA8 framebuffer
//                        of the host's, blitted to framebuffer 0
//   srgb-none.rgba, srgb-layers.rgba, srgb-layers-fbo.rgba
//                        the gamma-correct variant: no MSAA; two layers and
//                        the forward target into framebuffer 0; the same
//                        lit into an SRGB8_ALPHA8 framebuffer of the host's
//   reference.rgba, srgb-reference.rgba
//                        each variant's own 16x image: the frame at 4x the
//                        width and height in a framebuffer of its own,
//                        averaged 4x4 in the light a screen emits (sRGB
//                        decoded, averaged, encoded)
// It also runs the second lighting the way the chapter's code invites
// (dmsaa_begin_second_layer into framebuffer 0 and the lighting quad
// again without its glClear: the depth test rejects every fragment) and
// prints the status that gives. Exit status non-zero, with a line saying
// why, on any failed check.
//
// Usage: glfw_tutorial_host OUT_DIR [--egl]
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <GL/glcorearb.h>

#include "deferred_msaa.h"

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

#define DECLARE(type, name) static type name;
GL_FUNCTIONS(DECLARE)
#undef DECLARE

static bool loadGL()
{
    bool ok = true;
#define LOAD(type, name)                                                  \
    name = reinterpret_cast<type>(glfwGetProcAddress(#name));             \
    if (!name) {                                                          \
        std::fprintf(stderr, "glfw_tutorial_host: no %s\n", #name);       \
        ok = false;                                                       \
    }
    GL_FUNCTIONS(LOAD)
#undef LOAD
    return ok;
}

// The library gets GL the same way: a one-line function of its loader type.
static const void *loadForLibrary(const char *name, void *)
{
    return reinterpret_cast<const void *>(glfwGetProcAddress(name));
}

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

static bool ok(DmsaaStatus status, const char *call)
{
    if (status != DMSAA_STATUS_OK) {
        std::fprintf(stderr, "%s: status %d: %s\n", call, static_cast<int>(status), dmsaa_last_error());
        failures++;
        return false;
    }
    return true;
}

static void checkGlErrors(const char *where)
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

static Mat4 perspective(float fovy, float aspect, float zNear, float zFar)
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

static Vec3 sub(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
static Vec3 cross(Vec3 a, Vec3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
static Vec3 normalize(Vec3 v)
{
    float l = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
    return {v.x / l, v.y / l, v.z / l};
}
static float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

static Mat4 lookAt(Vec3 eye, Vec3 center, Vec3 up)
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

static Mat4 translate(Vec3 t)
{
    Mat4 r = Mat4::identity();
    r.m[12] = t.x; r.m[13] = t.y; r.m[14] = t.z;
    return r;
}

static Mat4 scale(float s)
{
    Mat4 r = Mat4::identity();
    r.m[0] = r.m[5] = r.m[10] = s;
    return r;
}

static Mat4 rotate(float angle, Vec3 axis)
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
static void renderCube()
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
static void renderQuad()
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

static GLuint makeTexture(int w, int h, GLint internal, GLenum type)
{
    GLuint t;
    glGenTextures(1, &t);
    glBindTexture(GL_TEXTURE_2D, t);
    glTexImage2D(GL_TEXTURE_2D, 0, internal, w, h, 0, GL_RGBA, type, NULL);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    return t;
}

static void engineInit(Engine &e, int width, int height, bool gammaCorrect)
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

static void engineFree(Engine &e)
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
static void geometryPass(Engine &e, GLuint target)
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
static void lightingQuad(Engine &e)
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
static void blitDepth(Engine &e, GLuint screen)
{
    glBindFramebuffer(GL_READ_FRAMEBUFFER, e.gBuffer);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, screen);
    glBlitFramebuffer(0, 0, e.width, e.height, 0, 0, e.width, e.height, GL_DEPTH_BUFFER_BIT, GL_NEAREST);
    glBindFramebuffer(GL_FRAMEBUFFER, screen);
}

// 3. render lights on top of scene (into whatever framebuffer is bound)
static void lightCubes(Engine &e)
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

// ---------------------------------------------------------------------------
// The variants of the frame: how the retrofit is used, and where the
// lighting goes.
struct Variant {
    uint32_t layers = 0;      // 0: no retrofit
    bool forward = false;     // the light cubes into the forward target
    GLuint litFbo = 0;        // the lighting's target: 0, or an FBO of the host's (blitted to 0)
};

static DmsaaOptions tutorialOptions(uint32_t layers)
{
    // As docs/capi.md and docs/hosts.md say for this program: world-space
    // positions in gPosition are the depth key, gNormal holds normals
    // (selected, and the clusters split by them).
    DmsaaOptions options = dmsaa_options_default();
    options.layers = layers;
    options.position_attachment = 0;
    options.world_space_position = 1;
    options.normal_attachment = 1;
    options.normal_encoding = DMSAA_NORMAL_XYZ;
    options.rules[1] = DMSAA_RULE_SELECT;
    // Its lighting writes display values as they are (no tonemap, no
    // encoding by GL unless the gamma-correct variant turns it on).
    options.layer_mix = DMSAA_LAYER_MIX_SRGB_ENCODED;
    return options;
}

// One frame of the program, as its render loop draws it.
static void frame(Engine &e, const Variant &v, DmsaaRetrofit *msaa)
{
    glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    if (e.gammaCorrect)
        glEnable(GL_FRAMEBUFFER_SRGB);

    GLuint geometryTarget = e.gBuffer;
    if (msaa)
        ok(dmsaa_framebuffer(msaa, &geometryTarget), "dmsaa_framebuffer");
    geometryPass(e, geometryTarget);
    if (msaa)
        ok(dmsaa_resolve(msaa, e.projection.m.data(), e.view.m.data()), "dmsaa_resolve");

    // 2. lighting pass
    glBindFramebuffer(GL_FRAMEBUFFER, v.litFbo);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    lightingQuad(e);
    if (msaa && v.layers == 2) {
        GLuint target = 0;
        if (ok(dmsaa_begin_second_layer_own_target(msaa, v.litFbo, &target),
               "dmsaa_begin_second_layer_own_target")) {
            CHECK(target != 0, "two layers, yet no target for the second lighting");
            glBindFramebuffer(GL_FRAMEBUFFER, target);
            glEnable(GL_STENCIL_TEST);
            glStencilFunc(GL_EQUAL, DMSAA_SECOND_LAYER_SELECTED, 0xFF);
            glStencilMask(0x00);
            lightingQuad(e);
            glStencilMask(0xFF);
            glDisable(GL_STENCIL_TEST);
            ok(dmsaa_finish_second_layer(msaa, v.litFbo), "dmsaa_finish_second_layer");
        }
    }
    if (v.litFbo != 0) {
        // The lit image onto the screen as it is stored (no sRGB conversion).
        glDisable(GL_FRAMEBUFFER_SRGB);
        glBindFramebuffer(GL_READ_FRAMEBUFFER, v.litFbo);
        glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
        glBlitFramebuffer(0, 0, e.width, e.height, 0, 0, e.width, e.height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
        if (e.gammaCorrect)
            glEnable(GL_FRAMEBUFFER_SRGB);
    }

    // 2.5 and 3: the forward part, into framebuffer 0
    blitDepth(e, 0);
    GLuint forwardTarget = 0;
    if (msaa && v.forward && ok(dmsaa_begin_forward(msaa, 0, &forwardTarget), "dmsaa_begin_forward"))
        glBindFramebuffer(GL_FRAMEBUFFER, forwardTarget);
    lightCubes(e);
    if (forwardTarget != 0)
        ok(dmsaa_finish_forward(msaa, 0), "dmsaa_finish_forward");
    glDisable(GL_FRAMEBUFFER_SRGB);
}

static std::vector<unsigned char> readScreen(int w, int h)
{
    std::vector<unsigned char> pixels(static_cast<size_t>(w) * static_cast<size_t>(h) * 4);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    glReadBuffer(GL_BACK);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, pixels.data());
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    return pixels;
}

static void writeImage(const std::string &dir, const char *name, const std::vector<unsigned char> &pixels)
{
    std::string path = dir + "/" + name;
    FILE *f = std::fopen(path.c_str(), "wb");
    CHECK(f != nullptr, "cannot write %s", path.c_str());
    if (f) {
        std::fwrite(pixels.data(), 1, pixels.size(), f);
        std::fclose(f);
    }
}

// A framebuffer of the host's with one colour texture and a depth
// renderbuffer, for the lighting (or for the supersampled frame).
struct Screen {
    GLuint fbo = 0, color = 0, depth = 0;
};

static Screen makeScreen(int w, int h, GLint internal)
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

static void freeScreen(Screen &s)
{
    glDeleteFramebuffers(1, &s.fbo);
    glDeleteTextures(1, &s.color);
    glDeleteRenderbuffers(1, &s.depth);
}

static double decode(unsigned char v)
{
    double c = v / 255.0;
    return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

static unsigned char encode(double l)
{
    double c = l <= 0.0031308 ? l * 12.92 : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055;
    return static_cast<unsigned char>(std::lround(std::fmin(std::fmax(c, 0.0), 1.0) * 255.0));
}

// The variant's own 16x image: every pass at 4x the width and height into
// a framebuffer of its own (as the lit target and the screen), averaged
// 4x4 in the light a screen emits.
static std::vector<unsigned char> supersampled(bool gammaCorrect)
{
    Engine big;
    int w = SCR_WIDTH * SUPERSAMPLE, h = SCR_HEIGHT * SUPERSAMPLE;
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
    glViewport(0, 0, SCR_WIDTH, SCR_HEIGHT);
    freeScreen(screen);
    engineFree(big);
    std::vector<unsigned char> small(static_cast<size_t>(SCR_WIDTH) * SCR_HEIGHT * 4);
    for (int y = 0; y < SCR_HEIGHT; y++)
        for (int x = 0; x < SCR_WIDTH; x++)
            for (int c = 0; c < 4; c++) {
                double sum = 0.0;
                for (int dy = 0; dy < SUPERSAMPLE; dy++)
                    for (int dx = 0; dx < SUPERSAMPLE; dx++) {
                        size_t i = ((static_cast<size_t>(y * SUPERSAMPLE + dy) * static_cast<size_t>(w)) +
                                    static_cast<size_t>(x * SUPERSAMPLE + dx)) * 4 + static_cast<size_t>(c);
                        sum += c == 3 ? pixels[i] / 255.0 : decode(pixels[i]);
                    }
                double mean = sum / (SUPERSAMPLE * SUPERSAMPLE);
                small[(static_cast<size_t>(y) * SCR_WIDTH + static_cast<size_t>(x)) * 4 + static_cast<size_t>(c)] =
                    c == 3 ? static_cast<unsigned char>(std::lround(mean * 255.0)) : encode(mean);
            }
    return small;
}

// Render one variant into framebuffer 0 and read it back.
static std::vector<unsigned char> render(Engine &e, const Variant &v, const char *name)
{
    DmsaaRetrofit *msaa = nullptr;
    if (v.layers > 0) {
        DmsaaOptions options = tutorialOptions(v.layers);
        if (!ok(dmsaa_retrofit_new(loadForLibrary, nullptr, e.gBuffer, &options, &msaa), "dmsaa_retrofit_new"))
            msaa = nullptr;
    }
    frame(e, v, msaa);
    checkGlErrors(name);
    std::vector<unsigned char> pixels = readScreen(e.width, e.height);
    if (msaa) {
        dmsaa_destroy(msaa);
        CHECK(dmsaa_live_objects() == 0, "%lld GL objects of the library left after dmsaa_destroy",
              static_cast<long long>(dmsaa_live_objects()));
    }
    return pixels;
}

// The second lighting as the chapter's code invites it: into framebuffer
// 0 again, the quad drawn again without the glClear in front of it. The
// depth test (on all frame) rejects every fragment against the depth the
// first quad wrote: the library must say so.
static void naiveSecondLighting(Engine &e)
{
    DmsaaOptions options = tutorialOptions(2);
    DmsaaRetrofit *msaa = nullptr;
    if (!ok(dmsaa_retrofit_new(loadForLibrary, nullptr, e.gBuffer, &options, &msaa), "dmsaa_retrofit_new"))
        return;
    glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
    GLuint fbo = 0;
    ok(dmsaa_framebuffer(msaa, &fbo), "dmsaa_framebuffer");
    geometryPass(e, fbo);
    ok(dmsaa_resolve(msaa, e.projection.m.data(), e.view.m.data()), "dmsaa_resolve");
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    lightingQuad(e);
    bool runLighting = false;
    ok(dmsaa_begin_second_layer(msaa, 0, &runLighting), "dmsaa_begin_second_layer");
    if (runLighting) {
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        lightingQuad(e);
        DmsaaStatus status = dmsaa_finish_second_layer(msaa, 0);
        std::printf("naive second lighting: status %d: %s\n", static_cast<int>(status),
                    status == DMSAA_STATUS_OK ? "" : dmsaa_last_error());
        CHECK(status == DMSAA_STATUS_SECOND_LIGHTING,
              "a second lighting the depth test rejected returned status %d, not DMSAA_STATUS_SECOND_LIGHTING",
              static_cast<int>(status));
    }
    checkGlErrors("the naive second lighting");
    dmsaa_destroy(msaa);
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s OUT_DIR [--egl]\n", argv[0]);
        return 2;
    }
    std::string dir = argv[1];
    bool egl = argc > 2 && std::strcmp(argv[2], "--egl") == 0;

    glfwInit();
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 2);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GL_TRUE);
    glfwWindowHint(GLFW_SRGB_CAPABLE, GLFW_TRUE);
    glfwWindowHint(GLFW_RESIZABLE, GLFW_FALSE);
    if (egl)
        glfwWindowHint(GLFW_CONTEXT_CREATION_API, GLFW_EGL_CONTEXT_API);
    GLFWwindow *window = glfwCreateWindow(SCR_WIDTH, SCR_HEIGHT, "LearnOpenGL", NULL, NULL);
    if (window == NULL) {
        const char *why = nullptr;
        glfwGetError(&why);
        std::fprintf(stderr, "Failed to create GLFW window: %s\n", why ? why : "?");
        glfwTerminate();
        return 3;
    }
    glfwMakeContextCurrent(window);
    if (!loadGL()) {
        std::fprintf(stderr, "Failed to initialize GLAD\n");
        return 3;
    }
    GLint major = 0, minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    if (major * 10 + minor < 33)
        glslVersion = "#version 150 core\n#extension GL_ARB_explicit_attrib_location : require\n";
    int fbWidth = 0, fbHeight = 0;
    glfwGetFramebufferSize(window, &fbWidth, &fbHeight);
    CHECK(fbWidth == SCR_WIDTH && fbHeight == SCR_HEIGHT, "the window's framebuffer is %dx%d", fbWidth, fbHeight);
    GLint encoding = 0;
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glGetFramebufferAttachmentParameteriv(GL_FRAMEBUFFER, GL_BACK_LEFT, GL_FRAMEBUFFER_ATTACHMENT_COLOR_ENCODING,
                                          &encoding);
    std::printf("GL %s through %s\n", reinterpret_cast<const char *>(glGetString(GL_VERSION)), egl ? "EGL" : "GLX");
    std::printf("framebuffer 0: %s encoding\n", encoding == GL_SRGB ? "sRGB" : "linear");
    std::printf("image %dx%d\n", SCR_WIDTH, SCR_HEIGHT);
    glViewport(0, 0, SCR_WIDTH, SCR_HEIGHT);

    {
        Engine e;
        engineInit(e, SCR_WIDTH, SCR_HEIGHT, false);
        Screen rgba8 = makeScreen(SCR_WIDTH, SCR_HEIGHT, GL_RGBA8);
        writeImage(dir, "none.rgba", render(e, Variant{0, false, 0}, "none"));
        writeImage(dir, "msaa.rgba", render(e, Variant{1, false, 0}, "one layer"));
        writeImage(dir, "forward.rgba", render(e, Variant{1, true, 0}, "one layer, forward target"));
        writeImage(dir, "layers.rgba", render(e, Variant{2, false, 0}, "two layers"));
        writeImage(dir, "layers-forward.rgba", render(e, Variant{2, true, 0}, "two layers, forward target"));
        writeImage(dir, "layers-fbo.rgba", render(e, Variant{2, false, rgba8.fbo}, "two layers lit into RGBA8"));
        naiveSecondLighting(e);
        freeScreen(rgba8);
        engineFree(e);
    }
    {
        Engine e;
        engineInit(e, SCR_WIDTH, SCR_HEIGHT, true);
        Screen srgb = makeScreen(SCR_WIDTH, SCR_HEIGHT, GL_SRGB8_ALPHA8);
        writeImage(dir, "srgb-none.rgba", render(e, Variant{0, false, 0}, "gamma-correct, none"));
        writeImage(dir, "srgb-layers.rgba", render(e, Variant{2, true, 0}, "gamma-correct, two layers"));
        writeImage(dir, "srgb-layers-fbo.rgba",
                   render(e, Variant{2, true, srgb.fbo}, "gamma-correct, two layers lit into SRGB8_ALPHA8"));
        freeScreen(srgb);
        engineFree(e);
    }
    writeImage(dir, "reference.rgba", supersampled(false));
    writeImage(dir, "srgb-reference.rgba", supersampled(true));
    checkGlErrors("the supersampled frames");
    glfwSwapBuffers(window);
    glfwTerminate();
    if (failures) {
        std::fprintf(stderr, "%d check(s) failed\n", failures);
        return 1;
    }
    std::printf("ok\n");
    return 0;
}
