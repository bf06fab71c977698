// The LearnOpenGL "Deferred Shading" chapter's program as its readers
// write it (tutorial_program.hpp), run as a render loop: a GLFW window,
// each frame the geometry pass into the G-buffer, the lighting quad into
// framebuffer 0, the G-buffer's depth blitted to it, the light cubes drawn
// forward, and the swap. Built two ways from this one source:
//
//   without DMSAA_IN_SOURCE  no line of the retrofit: what
//                            `deferred-msaa inject` is run on;
//   with -DDMSAA_IN_SOURCE   the retrofit added in the source as
//                            docs/capi.md says (dmsaa_framebuffer for the
//                            geometry pass, dmsaa_resolve after it), made
//                            before the first frame; with two layers, the
//                            lighting quad drawn again into
//                            dmsaa_begin_second_layer_own_target's
//                            framebuffer, then dmsaa_finish_second_layer;
//                            with --forward, the light cubes drawn into
//                            dmsaa_begin_forward's framebuffer, then
//                            dmsaa_finish_forward.
//
// Built with -DTUTORIAL_SDL, the window and the loader are SDL2's; with
// -DTUTORIAL_LINK_GL (and -lGL), GL is called through libGL's symbols.
//
// It draws FRAMES frames and writes the last one, read back from the back
// buffer before its swap, as raw RGBA8 (rows bottom-up) into OUT_FILE.
// Exit status non-zero, with a line saying why, on a GL error or a failed
// call.
//
// Usage: inject_tutorial OUT_FILE [--egl] [--tutorial-options] [--two-layers] [--forward]
//                       [--resize | --recreate] [--pre-pass]
//   --egl               the context through EGL (GLFW_EGL_CONTEXT_API)
//   --tutorial-options  (in-source build) the options
//                       crates/inject/profiles/tutorial.toml declares,
//                       rather than dmsaa_options_default()
//   --two-layers        (in-source build) two layers
//   --forward           (in-source build) the light cubes into the forward
//                       target, as `deferred-msaa inject` draws them
//   --camera-block      the projection and view in a uniform block
//                       (`Camera`, std140, binding 0: projection then view),
//                       written with glBufferSubData each frame, as engines
//                       keep their camera: no shader has a `projection`
//                       uniform (the in-source build passes the matrices)
//   --light-volumes     the lighting as engines with light volumes draw it:
//                       an ambient quad, then one quad per light, each added
//                       to what the clear left (depth test off, blending on,
//                       depth writes off for the lights), each light's values
//                       set as uniforms before its draw; the in-source build
//                       clears its second lighting's target as it clears
//                       framebuffer 0 before lighting
//   --light-block       (with --light-volumes) each light's values in a
//                       uniform block (`LightBlock`, std140, binding 1),
//                       written with glBufferSubData before its draw, as
//                       engines keep per-light data, not as uniforms
//   --reference FILE    also write the program's 16x image (every pass at 4x
//                       the width and height, averaged 4x4 in the light a
//                       screen emits) to FILE, raw RGBA8, rows bottom-up,
//                       and its last frame's edge pixels (edgeMask) to
//                       FILE.edges
//   --named-writes      (with --light-block) those writes made with
//                       glNamedBufferSubData, as GL 4.5 engines make them,
//                       the buffer never bound for them; exits 4 on a
//                       context older than 4.5
//   --two-pass-lighting the lighting in two passes, as engines with an
//                       accumulation target light: into an RGBA16F target of
//                       its own (cleared first), then a compose quad copying
//                       it into framebuffer 0; the in-source build's second
//                       lighting is both passes again, the compose into its
//                       own target
//   --float-lit         the lighting and the light cubes into an RGBA16F
//                       target of the program's (with its own depth), then
//                       blitted to framebuffer 0, as HDR engines light; its
//                       forward target, with nothing declared, is refused
//                       (DMSAA_STATUS_LAYER_MIX_UNDECLARED) and the cubes
//                       stay single-sampled, in-source as under inject
//   --view-projection   the camera as one `viewProjection` uniform (the
//                       product, made on the CPU), as engines upload it: no
//                       shader has a `projection` uniform
//   --resize            before the last frame (the injected program is
//                       retrofitted by then), the G-buffer's textures and
//                       depth made anew at RESIZED_WIDTH x RESIZED_HEIGHT and
//                       attached to it, the viewport with them (the in-source
//                       build then calls dmsaa_refresh)
//   --pre-pass          a pass between the G-buffer and the lighting (where
//                       SSAO would be), into a framebuffer of its own that
//                       the lighting does not read: the lighting is the
//                       second pass after the resolve
//   --recreate          before the second frame, the G-buffer deleted and
//                       made again (the in-source build destroys its
//                       retrofit and makes a new one)
//   --dsa               the G-buffer made through direct state access, as
//                       GL 4.5 engines make it (glCreateFramebuffers,
//                       glCreateTextures and glTextureStorage2D,
//                       glNamedFramebufferTexture, glNamedFramebufferRenderbuffer,
//                       glNamedFramebufferDrawBuffers), the depth copied with
//                       glBlitNamedFramebuffer; with --resize, a new G-buffer
//                       of the new size made under a new name and the old one
//                       deleted (the in-source build calls
//                       dmsaa_refresh_with); exits 4 on a context older than 4.5
#include "tutorial_program.hpp"
#include "tutorial_dsa.hpp"

#ifdef DMSAA_IN_SOURCE
#include "deferred_msaa.h"
#endif

static const int WIDTH = 160;
static const int HEIGHT = 120;
// The injected program is retrofitted from its second frame on (the
// G-buffer is known once the first frame's lighting has read it); the
// last frame is the third in both builds.
static const int FRAMES = 3;
static const int RESIZED_WIDTH = 128;
static const int RESIZED_HEIGHT = 96;

// The pre-pass: a quad reading gPosition into a texture of its own.
static const char *prePassFs = R"(
out vec4 FragColor;
in vec2 TexCoords;
uniform sampler2D gPosition;
void main()
{
    FragColor = vec4(fract(texture(gPosition, TexCoords).rgb), 1.0);
}
)";

// The camera as a uniform block, in place of the shaders' two uniforms.
static const char *cameraBlock = R"(
layout(std140) uniform Camera
{
    mat4 projection;
    mat4 view;
};
)";

// `text` with `from` replaced by `to` (a check fails where it is not found).
static std::string replaced(std::string text, const char *from, const char *to)
{
    size_t at = text.find(from);
    CHECK(at != std::string::npos, "a shader variant's text to replace was not found");
    if (at != std::string::npos)
        text.replace(at, std::strlen(from), to);
    return text;
}

// The tutorial's vertex shaders with the camera's uniforms replaced by
// `declaration` and its product by `product`.
static std::string gBufferVariant(const char *declaration, const char *product)
{
    return replaced(replaced(gBufferVs, "uniform mat4 view;\nuniform mat4 projection;\n", declaration),
                    "projection * view * worldPos", product);
}
static std::string lightBoxVariant(const char *declaration, const char *product)
{
    return replaced(replaced(lightBoxVs, "uniform mat4 projection;\nuniform mat4 view;\n", declaration),
                    "projection * view * model", product);
}



// The engine's shaders made anew with the view-projection uniform.
static void useViewProjection(Engine &e)
{
    glDeleteProgram(e.shaderGeometryPass->ID);
    glDeleteProgram(e.shaderLightBox->ID);
    delete e.shaderGeometryPass;
    delete e.shaderLightBox;
    std::string vs = gBufferVariant("uniform mat4 viewProjection;\n", "viewProjection * worldPos");
    std::string box = lightBoxVariant("uniform mat4 viewProjection;\n", "viewProjection * model");
    e.shaderGeometryPass = new Shader(vs.c_str(), gBufferFs);
    e.shaderLightBox = new Shader(box.c_str(), lightBoxFs);
}

// What the shared loader does not list, the program loads itself: through
// its window library's loader, or, linked with libGL, through GLX's
// get-proc-address called by name (its prototype as libGL exports it).
#ifdef TUTORIAL_LINK_GL
extern "C" void (*glXGetProcAddressARB(const GLubyte *name))(void);
#define PROGRAM_GET_PROC_ADDRESS(name) glXGetProcAddressARB(reinterpret_cast<const GLubyte *>(name))
#else
#define PROGRAM_GET_PROC_ADDRESS(name) TUTORIAL_GET_PROC_ADDRESS(name)
#endif

// The uniform-block functions, loaded by the program itself (the shared
// loader lists the tutorial's calls only).
static PFNGLBINDBUFFERBASEPROC cbBindBufferBase;
static PFNGLBUFFERSUBDATAPROC cbBufferSubData;
static PFNGLGETUNIFORMBLOCKINDEXPROC cbGetUniformBlockIndex;
static PFNGLUNIFORMBLOCKBINDINGPROC cbUniformBlockBinding;

// The lighting as light volumes: an ambient pass, then one light a draw.
static const char *ambientFs = R"(
out vec4 FragColor;
in vec2 TexCoords;
uniform sampler2D gAlbedoSpec;
void main()
{
    FragColor = vec4(texture(gAlbedoSpec, TexCoords).rgb * 0.1, 1.0);
}
)";
static const char *oneLightFs = R"(
out vec4 FragColor;
in vec2 TexCoords;
uniform sampler2D gPosition;
uniform sampler2D gNormal;
uniform sampler2D gAlbedoSpec;
uniform vec3 lightPosition;
uniform vec3 lightColor;
uniform float lightLinear;
uniform float lightQuadratic;
uniform vec3 viewPos;
void main()
{
    vec3 FragPos = texture(gPosition, TexCoords).rgb;
    vec3 Normal = texture(gNormal, TexCoords).rgb;
    vec3 Diffuse = texture(gAlbedoSpec, TexCoords).rgb;
    float Specular = texture(gAlbedoSpec, TexCoords).a;
    vec3 viewDir = normalize(viewPos - FragPos);
    vec3 lightDir = normalize(lightPosition - FragPos);
    vec3 diffuse = max(dot(Normal, lightDir), 0.0) * Diffuse * lightColor;
    vec3 halfwayDir = normalize(lightDir + viewDir);
    float spec = pow(max(dot(Normal, halfwayDir), 0.0), 16.0);
    vec3 specular = lightColor * spec * Specular;
    float distance = length(lightPosition - FragPos);
    float attenuation = 1.0 / (1.0 + lightLinear * distance + lightQuadratic * distance * distance);
    // A light's haze: the air it lights, on every pixel, background too.
    vec3 haze = lightColor * 0.02;
    FragColor = vec4((diffuse + specular) * attenuation + haze, 1.0);
}
)";

struct Volumes {
    Shader *ambient = nullptr, *oneLight = nullptr;
    // With --light-block: the lights' block and its buffer.
    GLuint lightBuffer = 0;
    // With --named-writes: glNamedBufferSubData (GL 4.5), the buffer never
    // bound to GL_UNIFORM_BUFFER for the write.
    PFNGLNAMEDBUFFERSUBDATAPROC namedBufferSubData = nullptr;
};

// The one-light shader's light in a uniform block instead.
static const char *lightBlockDecl = R"(
layout(std140) uniform LightBlock
{
    vec4 lightPositionBlock;
    vec4 lightColorBlock;
    vec4 lightFalloff;
};
#define lightPosition lightPositionBlock.xyz
#define lightColor lightColorBlock.rgb
#define lightLinear lightFalloff.x
#define lightQuadratic lightFalloff.y
)";

// The compose of the two-pass lighting: the accumulated light, as it is.
static const char *composeFs = R"(
out vec4 FragColor;
in vec2 TexCoords;
uniform sampler2D accumulated;
void main()
{
    FragColor = vec4(texture(accumulated, TexCoords).rgb, 1.0);
}
)";

// The two-pass lighting's accumulation target and compose.
struct Accumulation {
    GLuint framebuffer = 0, texture = 0;
    Shader *compose = nullptr;
};

// The lighting into the bound framebuffer, by `volumes` when it has its
// shaders, else the tutorial's one quad.
static void lighting(Engine &e, const Volumes &volumes)
{
    if (!volumes.ambient) {
        lightingQuad(e);
        return;
    }
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, e.gPosition);
    glActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, e.gNormal);
    glActiveTexture(GL_TEXTURE2);
    glBindTexture(GL_TEXTURE_2D, e.gAlbedoSpec);
    // Full-screen volumes: no depth test (the frame keeps it on elsewhere),
    // every term added to what the clear left.
    glDisable(GL_DEPTH_TEST);
    glEnable(GL_BLEND);
    glBlendFunc(GL_ONE, GL_ONE);
    volumes.ambient->use();
    volumes.ambient->setInt("gAlbedoSpec", 2);
    renderQuad();
    glDepthMask(GL_FALSE);
    volumes.oneLight->use();
    volumes.oneLight->setInt("gPosition", 0);
    volumes.oneLight->setInt("gNormal", 1);
    volumes.oneLight->setInt("gAlbedoSpec", 2);
    volumes.oneLight->setVec3("viewPos", cameraPosition);
    const bool named = volumes.namedBufferSubData != nullptr;
    if (volumes.lightBuffer) {
        cbBindBufferBase(GL_UNIFORM_BUFFER, 1, volumes.lightBuffer);
        if (!named)
            glBindBuffer(GL_UNIFORM_BUFFER, volumes.lightBuffer);
    }
    for (size_t i = 0; i < e.lightPositions.size(); i++) {
        if (volumes.lightBuffer) {
            const Vec3 p = e.lightPositions[i], c = e.lightColors[i];
            const float light[12] = {p.x, p.y, p.z, 1.0f, c.x, c.y, c.z, 1.0f, 0.7f, 1.8f, 0.0f, 0.0f};
            if (named)
                volumes.namedBufferSubData(volumes.lightBuffer, 0, sizeof light, light);
            else
                cbBufferSubData(GL_UNIFORM_BUFFER, 0, sizeof light, light);
        } else {
            volumes.oneLight->setVec3("lightPosition", e.lightPositions[i]);
            volumes.oneLight->setVec3("lightColor", e.lightColors[i]);
            volumes.oneLight->setFloat("lightLinear", 0.7f);
            volumes.oneLight->setFloat("lightQuadratic", 1.8f);
        }
        renderQuad();
    }
    if (volumes.lightBuffer && !named)
        glBindBuffer(GL_UNIFORM_BUFFER, 0);
    glDepthMask(GL_TRUE);
    glDisable(GL_BLEND);
    glEnable(GL_DEPTH_TEST);
}

// The compose pass: the accumulated light into the bound framebuffer.
static void compose(const Accumulation &a)
{
    a.compose->use();
    a.compose->setInt("accumulated", 0);
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, a.texture);
    renderQuad();
}


// The engine's shaders made anew with the camera block at binding 0.
static void useCameraBlock(Engine &e)
{
    std::string vs = gBufferVariant(cameraBlock, "projection * view * worldPos");
    std::string box = lightBoxVariant(cameraBlock, "projection * view * model");
    glDeleteProgram(e.shaderGeometryPass->ID);
    glDeleteProgram(e.shaderLightBox->ID);
    delete e.shaderGeometryPass;
    delete e.shaderLightBox;
    e.shaderGeometryPass = new Shader(vs.c_str(), gBufferFs);
    e.shaderLightBox = new Shader(box.c_str(), lightBoxFs);
    for (GLuint program : {e.shaderGeometryPass->ID, e.shaderLightBox->ID})
        cbUniformBlockBinding(program, cbGetUniformBlockIndex(program, "Camera"), 0);
}

// A resize as a program handles one: new textures and depth of the new
// size, attached to the same G-buffer.
static void resizeGBuffer(Engine &e, int width, int height)
{
    GLuint old[3] = {e.gPosition, e.gNormal, e.gAlbedoSpec};
    glDeleteTextures(3, old);
    glDeleteRenderbuffers(1, &e.rboDepth);
    e.width = width;
    e.height = height;
    glBindFramebuffer(GL_FRAMEBUFFER, e.gBuffer);
    e.gPosition = makeTexture(width, height, GL_RGBA16F, GL_FLOAT);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, e.gPosition, 0);
    e.gNormal = makeTexture(width, height, GL_RGBA16F, GL_FLOAT);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D, e.gNormal, 0);
    e.gAlbedoSpec = makeTexture(width, height, GL_RGBA, GL_UNSIGNED_BYTE);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT2, GL_TEXTURE_2D, e.gAlbedoSpec, 0);
    glGenRenderbuffers(1, &e.rboDepth);
    glBindRenderbuffer(GL_RENDERBUFFER, e.rboDepth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT, width, height);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, e.rboDepth);
    CHECK(glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE, "the resized G-buffer is incomplete");
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, width, height);
}

#ifdef DMSAA_IN_SOURCE
static const void *loadForLibrary(const char *name, void *)
{
    return reinterpret_cast<const void *>(TUTORIAL_GET_PROC_ADDRESS(name));
}

static bool ok(DmsaaStatus status, const char *call)
{
    if (status != DMSAA_STATUS_OK) {
        std::fprintf(stderr, "%s: status %d: %s\n", call, static_cast<int>(status), dmsaa_last_error());
        failures++;
        return false;
    }
    return true;
}
#endif

int main(int argc, char **argv)
{
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s OUT_FILE [--egl] [--tutorial-options] [--two-layers] [--forward] [--resize | --recreate] [--pre-pass] [--dsa]\n", argv[0]);
        return 2;
    }
    bool egl = false, tutorialOptions = false, twoLayers = false, forward = false, resize = false, recreate = false,
         prePass = false, cameraBlockOn = false, viewProjectionOn = false, lightVolumes = false,
         twoPass = false, lightBlock = false, floatLit = false, dsa = false, namedWrites = false;
    const char *referenceFile = nullptr;
    for (int i = 2; i < argc; i++) {
        if (std::strcmp(argv[i], "--egl") == 0)
            egl = true;
        else if (std::strcmp(argv[i], "--tutorial-options") == 0)
            tutorialOptions = true;
        else if (std::strcmp(argv[i], "--two-layers") == 0)
            twoLayers = true;
        else if (std::strcmp(argv[i], "--forward") == 0)
            forward = true;
        else if (std::strcmp(argv[i], "--camera-block") == 0)
            cameraBlockOn = true;
        else if (std::strcmp(argv[i], "--view-projection") == 0)
            viewProjectionOn = true;
        else if (std::strcmp(argv[i], "--light-volumes") == 0)
            lightVolumes = true;
        else if (std::strcmp(argv[i], "--two-pass-lighting") == 0)
            twoPass = true;
        else if (std::strcmp(argv[i], "--light-block") == 0)
            lightBlock = true;
        else if (std::strcmp(argv[i], "--named-writes") == 0)
            namedWrites = true;
        else if (std::strcmp(argv[i], "--reference") == 0 && i + 1 < argc)
            referenceFile = argv[++i];
        else if (std::strcmp(argv[i], "--float-lit") == 0)
            floatLit = true;
        else if (std::strcmp(argv[i], "--resize") == 0)
            resize = true;
        else if (std::strcmp(argv[i], "--recreate") == 0)
            recreate = true;
        else if (std::strcmp(argv[i], "--pre-pass") == 0)
            prePass = true;
        else if (std::strcmp(argv[i], "--dsa") == 0)
            dsa = true;
        else {
            std::fprintf(stderr, "unknown argument %s\n", argv[i]);
            return 2;
        }
    }
#ifdef TUTORIAL_SDL
    SDL_SetHint(SDL_HINT_VIDEO_X11_FORCE_EGL, egl ? "1" : "0");
    if (SDL_Init(SDL_INIT_VIDEO) != 0) {
        std::fprintf(stderr, "SDL_Init: %s\n", SDL_GetError());
        return 3;
    }
    SDL_GL_SetAttribute(SDL_GL_CONTEXT_MAJOR_VERSION, 3);
    SDL_GL_SetAttribute(SDL_GL_CONTEXT_MINOR_VERSION, 2);
    SDL_GL_SetAttribute(SDL_GL_CONTEXT_PROFILE_MASK, SDL_GL_CONTEXT_PROFILE_CORE);
    SDL_GL_SetAttribute(SDL_GL_CONTEXT_FLAGS, SDL_GL_CONTEXT_FORWARD_COMPATIBLE_FLAG);
    // GLFW's defaults: the depth blit needs formats that match.
    SDL_GL_SetAttribute(SDL_GL_DEPTH_SIZE, 24);
    SDL_GL_SetAttribute(SDL_GL_STENCIL_SIZE, 8);
    SDL_Window *window = SDL_CreateWindow("LearnOpenGL", SDL_WINDOWPOS_UNDEFINED, SDL_WINDOWPOS_UNDEFINED, WIDTH,
                                          HEIGHT, SDL_WINDOW_OPENGL);
    SDL_GLContext context = window ? SDL_GL_CreateContext(window) : nullptr;
    if (context == nullptr) {
        std::fprintf(stderr, "Failed to create an SDL window with a GL context: %s\n", SDL_GetError());
        SDL_Quit();
        return 3;
    }
    SDL_GL_MakeCurrent(window, context);
#else
    glfwInit();
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 2);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GL_TRUE);
    glfwWindowHint(GLFW_RESIZABLE, GLFW_FALSE);
    if (egl)
        glfwWindowHint(GLFW_CONTEXT_CREATION_API, GLFW_EGL_CONTEXT_API);
    GLFWwindow *window = glfwCreateWindow(WIDTH, HEIGHT, "LearnOpenGL", NULL, NULL);
    if (window == NULL) {
        const char *why = nullptr;
        glfwGetError(&why);
        std::fprintf(stderr, "Failed to create GLFW window: %s\n", why ? why : "?");
        glfwTerminate();
        return 3;
    }
    glfwMakeContextCurrent(window);
#endif
    if (!loadGL()) {
        std::fprintf(stderr, "Failed to initialize GLAD\n");
        return 3;
    }
    GLint major = 0, minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    if (major * 10 + minor < 33)
        glslVersion = "#version 150 core\n#extension GL_ARB_explicit_attrib_location : require\n";
    std::printf("GL %s through %s\n", reinterpret_cast<const char *>(glGetString(GL_VERSION)), egl ? "EGL" : "GLX");
    glViewport(0, 0, WIDTH, HEIGHT);

    cbBindBufferBase = reinterpret_cast<PFNGLBINDBUFFERBASEPROC>(PROGRAM_GET_PROC_ADDRESS("glBindBufferBase"));
    cbBufferSubData = reinterpret_cast<PFNGLBUFFERSUBDATAPROC>(PROGRAM_GET_PROC_ADDRESS("glBufferSubData"));
    cbGetUniformBlockIndex =
        reinterpret_cast<PFNGLGETUNIFORMBLOCKINDEXPROC>(PROGRAM_GET_PROC_ADDRESS("glGetUniformBlockIndex"));
    cbUniformBlockBinding =
        reinterpret_cast<PFNGLUNIFORMBLOCKBINDINGPROC>(PROGRAM_GET_PROC_ADDRESS("glUniformBlockBinding"));
    Engine e;
    engineInit(e, WIDTH, HEIGHT, false);
    if (dsa) {
        if (major * 10 + minor < 45 || !loadDsa()) {
            std::fprintf(stderr, "--dsa needs OpenGL 4.5 (direct state access); this context is %d.%d\n", major,
                         minor);
            return 4;
        }
        makeDsaGBuffer(e, WIDTH, HEIGHT);
    }
    Volumes volumes;
    if (lightVolumes) {
        volumes.ambient = new Shader(quadVs, ambientFs);
        if (lightBlock) {
            // The light's uniforms become the block's members.
            std::string fs = oneLightFs;
            const std::string from = "uniform vec3 lightPosition;\nuniform vec3 lightColor;\nuniform float lightLinear;\nuniform float lightQuadratic;\n";
            fs.replace(fs.find(from), from.size(), lightBlockDecl);
            volumes.oneLight = new Shader(quadVs, fs.c_str());
            cbUniformBlockBinding(volumes.oneLight->ID, cbGetUniformBlockIndex(volumes.oneLight->ID, "LightBlock"), 1);
            glGenBuffers(1, &volumes.lightBuffer);
            glBindBuffer(GL_UNIFORM_BUFFER, volumes.lightBuffer);
            glBufferData(GL_UNIFORM_BUFFER, 48, nullptr, GL_DYNAMIC_DRAW);
            glBindBuffer(GL_UNIFORM_BUFFER, 0);
            if (namedWrites) {
                volumes.namedBufferSubData = reinterpret_cast<PFNGLNAMEDBUFFERSUBDATAPROC>(
                    TUTORIAL_GET_PROC_ADDRESS("glNamedBufferSubData"));
                if (major * 10 + minor < 45 || !volumes.namedBufferSubData) {
                    std::fprintf(stderr, "--named-writes needs OpenGL 4.5 (direct state access); this context is %d.%d\n",
                                 major, minor);
                    return 4;
                }
            }
        } else {
            volumes.oneLight = new Shader(quadVs, oneLightFs);
        }
    }
    // The lit target: framebuffer 0, or with --float-lit an RGBA16F one.
    GLuint litTarget = 0, litColor = 0, litDepth = 0;
    if (floatLit) {
        glGenFramebuffers(1, &litTarget);
        glBindFramebuffer(GL_FRAMEBUFFER, litTarget);
        litColor = makeTexture(WIDTH, HEIGHT, GL_RGBA16F, GL_FLOAT);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, litColor, 0);
        glGenRenderbuffers(1, &litDepth);
        glBindRenderbuffer(GL_RENDERBUFFER, litDepth);
        glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT, WIDTH, HEIGHT);
        glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, litDepth);
        CHECK(glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE, "the lit target is incomplete");
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
    }
    Accumulation accumulation;
    if (twoPass) {
        glGenFramebuffers(1, &accumulation.framebuffer);
        glBindFramebuffer(GL_FRAMEBUFFER, accumulation.framebuffer);
        accumulation.texture = makeTexture(WIDTH, HEIGHT, GL_RGBA16F, GL_FLOAT);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, accumulation.texture, 0);
        CHECK(glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE, "the accumulation target is incomplete");
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        accumulation.compose = new Shader(quadVs, composeFs);
    }
    GLuint cameraBuffer = 0;
    if (viewProjectionOn)
        useViewProjection(e);
    if (cameraBlockOn) {
        useCameraBlock(e);
        glGenBuffers(1, &cameraBuffer);
        glBindBuffer(GL_UNIFORM_BUFFER, cameraBuffer);
        glBufferData(GL_UNIFORM_BUFFER, 128, nullptr, GL_DYNAMIC_DRAW);
        glBindBuffer(GL_UNIFORM_BUFFER, 0);
    }
#ifdef DMSAA_IN_SOURCE
    DmsaaOptions options = dmsaa_options_default();
    if (tutorialOptions) {
        // What crates/inject/profiles/tutorial.toml declares.
        options.position_attachment = 0;
        options.world_space_position = 1;
        options.normal_attachment = 1;
        options.normal_encoding = DMSAA_NORMAL_XYZ;
        options.rules[1] = DMSAA_RULE_SELECT;
        options.layer_mix = DMSAA_LAYER_MIX_SRGB_ENCODED;
    }
    options.layers = twoLayers ? 2 : 1;
    DmsaaRetrofit *msaa = nullptr;
    if (!ok(dmsaa_retrofit_new(loadForLibrary, nullptr, e.gBuffer, &options, &msaa), "dmsaa_retrofit_new"))
        return 1;
#else
    (void)tutorialOptions;
    (void)twoLayers;
    (void)forward;
#endif

    Shader prePassShader(quadVs, prePassFs);
    GLuint prePassFbo = 0, prePassColor = 0;
    glGenFramebuffers(1, &prePassFbo);
    glBindFramebuffer(GL_FRAMEBUFFER, prePassFbo);
    prePassColor = makeTexture(WIDTH, HEIGHT, GL_RGBA8, GL_UNSIGNED_BYTE);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, prePassColor, 0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);

    std::vector<unsigned char> pixels(static_cast<size_t>(WIDTH) * HEIGHT * 4);
    glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
    for (int frame = 0; frame < FRAMES; frame++) {
        if (frame == FRAMES - 1 && resize && dsa) {
            makeDsaGBuffer(e, RESIZED_WIDTH, RESIZED_HEIGHT);
#ifdef DMSAA_IN_SOURCE
            ok(dmsaa_refresh_with(msaa, e.gBuffer), "dmsaa_refresh_with");
#endif
        } else if (frame == FRAMES - 1 && resize) {
            resizeGBuffer(e, RESIZED_WIDTH, RESIZED_HEIGHT);
#ifdef DMSAA_IN_SOURCE
            ok(dmsaa_refresh(msaa), "dmsaa_refresh");
#endif
        }
        if (frame == 1 && recreate) {
#ifdef DMSAA_IN_SOURCE
            dmsaa_destroy(msaa);
            msaa = nullptr;
#endif
            engineFree(e);
            e = Engine();
            engineInit(e, WIDTH, HEIGHT, false);
            if (dsa)
                makeDsaGBuffer(e, WIDTH, HEIGHT);
            if (cameraBlockOn)
                useCameraBlock(e);
            if (viewProjectionOn)
                useViewProjection(e);
#ifdef DMSAA_IN_SOURCE
            if (!ok(dmsaa_retrofit_new(loadForLibrary, nullptr, e.gBuffer, &options, &msaa), "dmsaa_retrofit_new"))
                return 1;
#endif
        }
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        if (viewProjectionOn) {
            // The frame's camera as one product, into both programs.
            Mat4 viewProjection = e.projection * e.view;
            for (Shader *shader : {e.shaderGeometryPass, e.shaderLightBox}) {
                shader->use();
                shader->setMat4("viewProjection", viewProjection);
            }
        }
        if (cameraBlockOn) {
            // The frame's camera into its block, as engines update theirs.
            cbBindBufferBase(GL_UNIFORM_BUFFER, 0, cameraBuffer);
            glBindBuffer(GL_UNIFORM_BUFFER, cameraBuffer);
            cbBufferSubData(GL_UNIFORM_BUFFER, 0, 64, e.projection.m.data());
            cbBufferSubData(GL_UNIFORM_BUFFER, 64, 64, e.view.m.data());
            glBindBuffer(GL_UNIFORM_BUFFER, 0);
        }

        // 1. geometry pass
        GLuint geometryTarget = e.gBuffer;
#ifdef DMSAA_IN_SOURCE
        ok(dmsaa_begin_frame(msaa, &geometryTarget), "dmsaa_begin_frame");
#endif
        geometryPass(e, geometryTarget);
#ifdef DMSAA_IN_SOURCE
        ok(dmsaa_resolve(msaa, e.projection.m.data(), e.view.m.data()), "dmsaa_resolve");
#endif

        if (prePass) {
            glBindFramebuffer(GL_FRAMEBUFFER, prePassFbo);
            glClear(GL_COLOR_BUFFER_BIT);
            prePassShader.use();
            prePassShader.setInt("gPosition", 0);
            glActiveTexture(GL_TEXTURE0);
            glBindTexture(GL_TEXTURE_2D, e.gPosition);
            renderQuad();
        }

        // 2. lighting pass, 2.5 the depth copy, 3. the light cubes
        if (twoPass) {
            // The lights into the accumulation target, then the compose.
            glBindFramebuffer(GL_FRAMEBUFFER, accumulation.framebuffer);
            glClear(GL_COLOR_BUFFER_BIT);
            lighting(e, volumes);
        }
        glBindFramebuffer(GL_FRAMEBUFFER, litTarget);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        if (twoPass)
            compose(accumulation);
        else
            lighting(e, volumes);
#ifdef DMSAA_IN_SOURCE
        GLuint secondTarget = 0;
        if (twoLayers && ok(dmsaa_begin_second_layer_own_target(msaa, litTarget, &secondTarget),
                            "dmsaa_begin_second_layer_own_target")) {
            if (twoPass) {
                glBindFramebuffer(GL_DRAW_FRAMEBUFFER, accumulation.framebuffer);
                glClear(GL_COLOR_BUFFER_BIT);
                lighting(e, volumes);
                glBindFramebuffer(GL_DRAW_FRAMEBUFFER, secondTarget);
                compose(accumulation);
            } else {
                glBindFramebuffer(GL_DRAW_FRAMEBUFFER, secondTarget);
                // Additive lights start from the program's clear colour, as
                // the first lighting's framebuffer 0 did.
                if (lightVolumes)
                    glClear(GL_COLOR_BUFFER_BIT);
                lighting(e, volumes);
            }
            ok(dmsaa_finish_second_layer(msaa, litTarget), "dmsaa_finish_second_layer");
            glBindFramebuffer(GL_DRAW_FRAMEBUFFER, litTarget);
        }
#endif
        if (dsa) {
            dsaBlitNamedFramebuffer(e.gBuffer, litTarget, 0, 0, e.width, e.height, 0, 0, e.width, e.height,
                                    GL_DEPTH_BUFFER_BIT, GL_NEAREST);
            glBindFramebuffer(GL_FRAMEBUFFER, litTarget);
        } else {
            blitDepth(e, litTarget);
        }
#ifdef DMSAA_IN_SOURCE
        GLuint forwardTarget = 0;
        if (forward) {
            DmsaaStatus status = dmsaa_begin_forward(msaa, litTarget, &forwardTarget);
            // A float lit target with nothing declared: refused, as inject
            // is; the cubes stay single-sampled.
            if (!(floatLit && status == DMSAA_STATUS_LAYER_MIX_UNDECLARED) && ok(status, "dmsaa_begin_forward"))
                glBindFramebuffer(GL_FRAMEBUFFER, forwardTarget);
        }
#endif
        lightCubes(e);
#ifdef DMSAA_IN_SOURCE
        if (forwardTarget != 0)
            ok(dmsaa_finish_forward(msaa, litTarget), "dmsaa_finish_forward");
#endif
        if (floatLit) {
            // The HDR image onto the screen, as it is.
            glBindFramebuffer(GL_READ_FRAMEBUFFER, litTarget);
            glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
            glBlitFramebuffer(0, 0, WIDTH, HEIGHT, 0, 0, WIDTH, HEIGHT, GL_COLOR_BUFFER_BIT, GL_NEAREST);
            glBindFramebuffer(GL_FRAMEBUFFER, 0);
        }
        checkGlErrors("a frame");

        if (frame == FRAMES - 1) {
            glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
            glReadBuffer(GL_BACK);
            glPixelStorei(GL_PACK_ALIGNMENT, 1);
            glReadPixels(0, 0, WIDTH, HEIGHT, GL_RGBA, GL_UNSIGNED_BYTE, pixels.data());
            glPixelStorei(GL_PACK_ALIGNMENT, 4);
        }
#ifdef TUTORIAL_SDL
        SDL_GL_SwapWindow(window);
        for (SDL_Event event; SDL_PollEvent(&event);) {
        }
#else
        glfwSwapBuffers(window);
        glfwPollEvents();
#endif
    }
#ifdef DMSAA_IN_SOURCE
    dmsaa_destroy(msaa);
#endif
    if (cameraBuffer)
        glDeleteBuffers(1, &cameraBuffer);
    glDeleteFramebuffers(1, &prePassFbo);
    glDeleteTextures(1, &prePassColor);
    glDeleteProgram(prePassShader.ID);
    if (volumes.lightBuffer)
        glDeleteBuffers(1, &volumes.lightBuffer);
    if (litTarget) {
        glDeleteFramebuffers(1, &litTarget);
        glDeleteTextures(1, &litColor);
        glDeleteRenderbuffers(1, &litDepth);
    }
    if (accumulation.framebuffer) {
        glDeleteFramebuffers(1, &accumulation.framebuffer);
        glDeleteTextures(1, &accumulation.texture);
    }
    for (Shader *shader : {volumes.ambient, volumes.oneLight, accumulation.compose}) {
        if (shader) {
            glDeleteProgram(shader->ID);
            delete shader;
        }
    }
    std::vector<unsigned char> edges;
    if (referenceFile)
        edges = edgeMask(e);
    engineFree(e);
    if (referenceFile) {
        std::string edgesFile = std::string(referenceFile) + ".edges";
        FILE *m = std::fopen(edgesFile.c_str(), "wb");
        CHECK(m != nullptr, "cannot write %s", edgesFile.c_str());
        if (m) {
            std::fwrite(edges.data(), 1, edges.size(), m);
            std::fclose(m);
        }
        std::vector<unsigned char> reference = supersampled(WIDTH, HEIGHT, false);
        FILE *r = std::fopen(referenceFile, "wb");
        CHECK(r != nullptr, "cannot write %s", referenceFile);
        if (r) {
            std::fwrite(reference.data(), 1, reference.size(), r);
            std::fclose(r);
        }
    }
    checkGlErrors("the end");

    FILE *f = std::fopen(argv[1], "wb");
    CHECK(f != nullptr, "cannot write %s", argv[1]);
    if (f) {
        std::fwrite(pixels.data(), 1, pixels.size(), f);
        std::fclose(f);
    }
#ifdef TUTORIAL_SDL
    SDL_GL_DeleteContext(context);
    SDL_DestroyWindow(window);
    SDL_Quit();
#else
    glfwTerminate();
#endif
    if (failures) {
        std::fprintf(stderr, "%d check(s) failed\n", failures);
        return 1;
    }
    std::printf("ok\n");
    return 0;
}
