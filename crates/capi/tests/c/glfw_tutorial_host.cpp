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
// bound through dmsaa_begin_frame and dmsaa_resolve after the geometry
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
//   layers-forward-{auto,linear,tonemapped}.rgba, srgb-layers-{auto,linear,tonemapped}.rgba
//                        two layers and the forward target with layer_mix
//                        left to DMSAA_LAYER_MIX_AUTO or declared otherwise,
//                        for the test to measure against the declaration
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
#include "tutorial_program.hpp"

#include "deferred_msaa.h"

static const void *loadForLibrary(const char *name, void *)
{
    return reinterpret_cast<const void *>(glfwGetProcAddress(name));
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

// ---------------------------------------------------------------------------
// The variants of the frame: how the retrofit is used, and where the
// lighting goes.
struct Variant {
    uint32_t layers = 0;      // 0: no retrofit
    bool forward = false;     // the light cubes into the forward target
    GLuint litFbo = 0;        // the lighting's target: 0, or an FBO of the host's (blitted to 0)
    int mix = -1;             // -1: the program's layer_mix; else a DMSAA_LAYER_MIX_* to measure
};

static DmsaaOptions tutorialOptions(uint32_t layers, int mix = -1)
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
    if (mix >= 0)
        options.layer_mix = static_cast<DmsaaLayerMix>(mix);
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
        ok(dmsaa_begin_frame(msaa, &geometryTarget), "dmsaa_begin_frame");
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

// The screenshot as the program takes it right after its frame: it binds
// nothing, since it drew into framebuffer 0 last (its light cubes; with the
// library, into the forward target, which dmsaa_finish_forward replaces by
// framebuffer 0 as if the cubes had been drawn there). A GL error here is a
// black screenshot.
static std::vector<unsigned char> readScreen(int w, int h)
{
    std::vector<unsigned char> pixels(static_cast<size_t>(w) * static_cast<size_t>(h) * 4);
    glReadBuffer(GL_BACK);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, pixels.data());
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    checkGlErrors("the read-back right after the frame (glReadBuffer(GL_BACK), glReadPixels)");
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

// Render one variant into framebuffer 0 and read it back.
static std::vector<unsigned char> render(Engine &e, const Variant &v, const char *name)
{
    DmsaaRetrofit *msaa = nullptr;
    if (v.layers > 0) {
        DmsaaOptions options = tutorialOptions(v.layers, v.mix);
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
    ok(dmsaa_begin_frame(msaa, &fbo), "dmsaa_begin_frame");
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
        writeImage(dir, "layers-forward-auto.rgba",
                   render(e, Variant{2, true, 0, DMSAA_LAYER_MIX_AUTO}, "two layers, forward target, nothing declared"));
        writeImage(dir, "layers-forward-linear.rgba",
                   render(e, Variant{2, true, 0, DMSAA_LAYER_MIX_LINEAR}, "two layers, forward target, linear"));
        writeImage(dir, "layers-forward-tonemapped.rgba",
                   render(e, Variant{2, true, 0, DMSAA_LAYER_MIX_TONEMAPPED}, "two layers, forward target, tonemapped"));
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
        writeImage(dir, "srgb-layers-auto.rgba",
                   render(e, Variant{2, true, 0, DMSAA_LAYER_MIX_AUTO}, "gamma-correct, two layers, nothing declared"));
        writeImage(dir, "srgb-layers-linear.rgba",
                   render(e, Variant{2, true, 0, DMSAA_LAYER_MIX_LINEAR}, "gamma-correct, two layers, linear"));
        writeImage(dir, "srgb-layers-tonemapped.rgba",
                   render(e, Variant{2, true, 0, DMSAA_LAYER_MIX_TONEMAPPED}, "gamma-correct, two layers, tonemapped"));
        freeScreen(srgb);
        engineFree(e);
    }
    writeImage(dir, "reference.rgba", supersampled(SCR_WIDTH, SCR_HEIGHT, false));
    writeImage(dir, "srgb-reference.rgba", supersampled(SCR_WIDTH, SCR_HEIGHT, true));
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
