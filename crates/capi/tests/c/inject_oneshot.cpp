// The LearnOpenGL deferred-shading program (tutorial_program.hpp) as the
// programs that render to a file are written: a screenshot harness, or an
// engine's one-call render. Its `render` does the whole of one image: it
// makes the G-buffer (engineInit), draws the geometry pass into it, the
// lighting into an output framebuffer of its own (an RGBA8 texture), reads
// that back, and deletes the G-buffer and everything else it made
// (engineFree). Nothing of the retrofit is in it: it is what
// `deferred-msaa inject` is run on, to show the line the library says when
// it leaves such a program alone.
//
// Usage: inject_oneshot OUT_FILE [--calls N] [--no-swap] [--keep [--clear-fbo [--clear-buffers]] [--clear-named]] [--array]
//   --calls N   call `render` N times (default 1: a screenshot harness)
//   --no-swap   never swap (as a surfaceless renderer does); otherwise the
//               window's buffers are swapped after each call
//   --keep      the G-buffer made once and kept: a render loop of N frames
//               writing its last (the tutorial's engine, with the output
//               framebuffer of its own)
//   --clear-fbo (with --keep) the G-buffer cleared as some engines clear
//               it: through a framebuffer of their own that shares its
//               textures and depth, not with the G-buffer bound (glClear)
//   --clear-buffers  (with --clear-fbo) that clear made per attachment,
//               each with its own value (glClearBufferfv)
//   --clear-named  (with --keep) the clear made per attachment by name,
//               through direct state access, as GL 4.5 engines make it
//               (glClearNamedFramebufferfv), of the clear framebuffer with
//               --clear-fbo, else of the G-buffer itself, never bound for
//               it; exits 4 on a context older than 4.5
//   --array     the G-buffer made once, as some engines make it: one
//               GL_TEXTURE_2D_ARRAY whose three layers are attached with
//               glFramebufferTextureLayer, read by the lighting as a
//               sampler2DArray (the tutorial's geometry pass draws into it)
//
// It writes the last image, raw RGBA8 (rows bottom-up), into OUT_FILE, and
// prints "ok" when no GL error or failed check was seen.
#include "tutorial_program.hpp"

static const int WIDTH = 160;
static const int HEIGHT = 120;

#ifndef TUTORIAL_LINK_GL
static PFNGLTEXIMAGE3DPROC glTexImage3D;
static PFNGLFRAMEBUFFERTEXTURELAYERPROC glFramebufferTextureLayer;
static PFNGLCLEARBUFFERFVPROC glClearBufferfv;
#endif
// Loaded by its own name whichever way GL is reached: a 4.5 function.
static PFNGLCLEARNAMEDFRAMEBUFFERFVPROC clearNamedFramebufferfv;

// The lighting of the array G-buffer: one light from above, on the albedo
// layer, by the normal layer.
static const char *arrayLightingFs = R"(
out vec4 FragColor;
in vec2 TexCoords;
uniform sampler2DArray gBuffer;
void main()
{
    vec3 normal = texture(gBuffer, vec3(TexCoords, 1.0)).rgb;
    vec3 albedo = texture(gBuffer, vec3(TexCoords, 2.0)).rgb;
    FragColor = vec4(albedo * (0.2 + max(dot(normal, normalize(vec3(0.3, 1.0, 0.5))), 0.0)), 1.0);
}
)";

// The array G-buffer's framebuffer and its objects.
struct ArrayGBuffer {
    GLuint framebuffer = 0, layers = 0, depth = 0;
    Shader *lighting = nullptr;
};

static ArrayGBuffer makeArrayGBuffer()
{
    ArrayGBuffer a;
    glGenTextures(1, &a.layers);
    glBindTexture(GL_TEXTURE_2D_ARRAY, a.layers);
    glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, GL_RGBA16F, WIDTH, HEIGHT, 3, 0, GL_RGBA, GL_FLOAT, NULL);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glGenFramebuffers(1, &a.framebuffer);
    glBindFramebuffer(GL_FRAMEBUFFER, a.framebuffer);
    for (int layer = 0; layer < 3; layer++)
        glFramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + static_cast<GLenum>(layer), a.layers, 0,
                                  layer);
    unsigned int attachments[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
    glDrawBuffers(3, attachments);
    glGenRenderbuffers(1, &a.depth);
    glBindRenderbuffer(GL_RENDERBUFFER, a.depth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT, WIDTH, HEIGHT);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, a.depth);
    CHECK(glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE, "the array G-buffer is incomplete");
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    a.lighting = new Shader(quadVs, arrayLightingFs);
    return a;
}

// The geometry pass with the G-buffer cleared through `clearFbo`, a
// framebuffer sharing its attachments, or by name (the tutorial's draws
// otherwise).
static void geometryPassClearedElsewhere(Engine &e, GLuint clearFbo, bool perAttachment, bool named)
{
    if (named) {
        const float none[4] = {0.0f, 0.0f, 0.0f, 0.0f};
        const float far = 1.0f;
        GLuint cleared = clearFbo ? clearFbo : e.gBuffer;
        for (int i = 0; i < 3; i++)
            clearNamedFramebufferfv(cleared, GL_COLOR, i, none);
        clearNamedFramebufferfv(cleared, GL_DEPTH, 0, &far);
    } else if (perAttachment) {
        glBindFramebuffer(GL_FRAMEBUFFER, clearFbo);
        const float none[4] = {0.0f, 0.0f, 0.0f, 0.0f};
        const float far = 1.0f;
        for (int i = 0; i < 3; i++)
            glClearBufferfv(GL_COLOR, i, none);
        glClearBufferfv(GL_DEPTH, 0, &far);
    } else {
        glBindFramebuffer(GL_FRAMEBUFFER, clearFbo);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    }
    glBindFramebuffer(GL_FRAMEBUFFER, e.gBuffer);
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

// The framebuffer an engine clears its G-buffer through: the same textures
// and depth.
static GLuint makeClearFbo(const Engine &e)
{
    GLuint fbo = 0;
    glGenFramebuffers(1, &fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, e.gPosition, 0);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D, e.gNormal, 0);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT2, GL_TEXTURE_2D, e.gAlbedoSpec, 0);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, e.rboDepth);
    unsigned int attachments[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
    glDrawBuffers(3, attachments);
    CHECK(glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE, "the clear framebuffer is incomplete");
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    return fbo;
}

// What a render draws with: made in each call, or kept across calls.
struct Kept {
    Engine *engine = nullptr;
    GLuint clearFbo = 0;
    bool clearBuffers = false;
    bool clearNamed = false;
};

// One image, start to end: the G-buffer made, used and deleted (with an
// array G-buffer, that one is drawn instead, and kept; with a kept engine,
// its G-buffer is drawn and kept).
static void render(std::vector<unsigned char> &pixels, const ArrayGBuffer *array, const Kept &kept)
{
    Engine own;
    if (!kept.engine)
        engineInit(own, WIDTH, HEIGHT, false);
    Engine &e = kept.engine ? *kept.engine : own;

    GLuint output = 0, outputColor = 0;
    glGenFramebuffers(1, &output);
    glBindFramebuffer(GL_FRAMEBUFFER, output);
    outputColor = makeTexture(WIDTH, HEIGHT, GL_RGBA8, GL_UNSIGNED_BYTE);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, outputColor, 0);
    CHECK(glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE, "the output is incomplete");

    if (kept.clearFbo || kept.clearNamed)
        geometryPassClearedElsewhere(e, kept.clearFbo, kept.clearBuffers, kept.clearNamed);
    else
        geometryPass(e, array ? array->framebuffer : e.gBuffer);
    glBindFramebuffer(GL_FRAMEBUFFER, output);
    glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    if (array) {
        array->lighting->use();
        array->lighting->setInt("gBuffer", 0);
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_2D_ARRAY, array->layers);
        renderQuad();
    } else {
        lightingQuad(e);
    }

    glBindFramebuffer(GL_READ_FRAMEBUFFER, output);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, WIDTH, HEIGHT, GL_RGBA, GL_UNSIGNED_BYTE, pixels.data());
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    checkGlErrors("render");

    glDeleteFramebuffers(1, &output);
    glDeleteTextures(1, &outputColor);
    if (!kept.engine)
        engineFree(own);
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s OUT_FILE [--calls N] [--no-swap] [--keep [--clear-fbo [--clear-buffers]]] [--array]\n", argv[0]);
        return 2;
    }
    int calls = 1;
    bool swap = true, useArray = false, keep = false, clearFbo = false, clearBuffers = false, clearNamed = false;
    for (int i = 2; i < argc; i++) {
        if (std::strcmp(argv[i], "--calls") == 0 && i + 1 < argc)
            calls = std::atoi(argv[++i]);
        else if (std::strcmp(argv[i], "--no-swap") == 0)
            swap = false;
        else if (std::strcmp(argv[i], "--array") == 0)
            useArray = true;
        else if (std::strcmp(argv[i], "--keep") == 0)
            keep = true;
        else if (std::strcmp(argv[i], "--clear-fbo") == 0)
            clearFbo = true;
        else if (std::strcmp(argv[i], "--clear-buffers") == 0)
            clearBuffers = true;
        else if (std::strcmp(argv[i], "--clear-named") == 0)
            clearNamed = true;
        else {
            std::fprintf(stderr, "unknown argument %s\n", argv[i]);
            return 2;
        }
    }
    glfwInit();
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 2);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GL_TRUE);
    glfwWindowHint(GLFW_VISIBLE, GLFW_FALSE);
    GLFWwindow *window = glfwCreateWindow(WIDTH, HEIGHT, "oneshot", NULL, NULL);
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
#ifndef TUTORIAL_LINK_GL
    glTexImage3D = reinterpret_cast<PFNGLTEXIMAGE3DPROC>(glfwGetProcAddress("glTexImage3D"));
    glFramebufferTextureLayer =
        reinterpret_cast<PFNGLFRAMEBUFFERTEXTURELAYERPROC>(glfwGetProcAddress("glFramebufferTextureLayer"));
    glClearBufferfv = reinterpret_cast<PFNGLCLEARBUFFERFVPROC>(glfwGetProcAddress("glClearBufferfv"));
#endif
    GLint major = 0, minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    if (major * 10 + minor < 33)
        glslVersion = "#version 150 core\n#extension GL_ARB_explicit_attrib_location : require\n";
    clearNamedFramebufferfv =
        reinterpret_cast<PFNGLCLEARNAMEDFRAMEBUFFERFVPROC>(glfwGetProcAddress("glClearNamedFramebufferfv"));
    if (clearNamed && (major * 10 + minor < 45 || !clearNamedFramebufferfv)) {
        std::fprintf(stderr, "--clear-named needs OpenGL 4.5 (direct state access); this context is %d.%d\n", major, minor);
        glfwTerminate();
        return 4;
    }
    glViewport(0, 0, WIDTH, HEIGHT);

    ArrayGBuffer array;
    if (useArray)
        array = makeArrayGBuffer();
    Engine keptEngine;
    Kept kept;
    if (keep) {
        engineInit(keptEngine, WIDTH, HEIGHT, false);
        kept.engine = &keptEngine;
        if (clearFbo)
            kept.clearFbo = makeClearFbo(keptEngine);
        kept.clearBuffers = clearBuffers;
        kept.clearNamed = clearNamed;
    }
    std::vector<unsigned char> pixels(static_cast<size_t>(WIDTH) * HEIGHT * 4);
    for (int call = 0; call < calls; call++) {
        render(pixels, useArray ? &array : nullptr, kept);
        if (swap)
            glfwSwapBuffers(window);
    }
    if (keep) {
        glDeleteFramebuffers(1, &kept.clearFbo);
        engineFree(keptEngine);
    }
    if (useArray) {
        glDeleteFramebuffers(1, &array.framebuffer);
        glDeleteTextures(1, &array.layers);
        glDeleteRenderbuffers(1, &array.depth);
        glDeleteProgram(array.lighting->ID);
        delete array.lighting;
    }

    FILE *f = std::fopen(argv[1], "wb");
    CHECK(f != nullptr, "cannot write %s", argv[1]);
    if (f) {
        std::fwrite(pixels.data(), 1, pixels.size(), f);
        std::fclose(f);
    }
    glfwTerminate();
    if (failures) {
        std::fprintf(stderr, "%d check(s) failed\n", failures);
        return 1;
    }
    std::printf("ok\n");
    return 0;
}
