/*
 * Every bad call a C host can make returns an error status with a
 * one-line message, and the process keeps running: null options, a null
 * handle, a zero FBO, an FBO without depth, the second layer's calls out
 * of order, a resolve of a frame not begun or of twins nothing cleared,
 * options out of range, a projection that is not one, a loader
 * without one GL function, a name that is no framebuffer. Each bad
 * call prints one line, "bad call: NAME: status S: MESSAGE"; a valid
 * retrofit made afterwards still resolves. Exits non-zero, saying why, if
 * any call succeeds that must not, returns another status than expected,
 * leaves an empty or multi-line message, or leaves GL objects behind.
 *
 * Usage: bad_calls
 */
#include "deferred_msaa.h"
#include "egl_gl.h"

#include <string.h>

static int failures = 0;
static int bad_calls = 0;

static void expect(DmsaaStatus got, DmsaaStatus expected, const char *name)
{
    const char *message = dmsaa_last_error();
    bad_calls++;
    printf("bad call: %s: status %d: %s\n", name, (int)got, message ? message : "(null)");
    if (got != expected) {
        fprintf(stderr, "FAIL: %s returned %d, expected %d\n", name, (int)got, (int)expected);
        failures++;
    }
    if (!message || !message[0] || strchr(message, '\n')) {
        fprintf(stderr, "FAIL: %s left no one-line message\n", name);
        failures++;
    }
}

/* A loader without the one function named by `user_data`. */
static const void *load_without(const char *name, void *user_data)
{
    if (strcmp(name, (const char *)user_data) == 0)
        return NULL;
    return load_gl(name, NULL);
}

/* Fails unless the last message holds `text` and no GL error is left. */
static void expect_message(const char *text, const char *name)
{
    if (!strstr(dmsaa_last_error(), text)) {
        fprintf(stderr, "FAIL: the message for %s does not say `%s`\n", name, text);
        failures++;
    }
    GLenum error = glGetError();
    if (error != GL_NO_ERROR) {
        fprintf(stderr, "FAIL: %s left GL error 0x%x\n", name, error);
        failures++;
    }
}

/* A frame as a host begins it: dmsaa_begin_frame, then its own clear of
   the framebuffer it gives (the geometry pass draws nothing here). */
static int begin_cleared(DmsaaRetrofit *msaa)
{
    uint32_t fbo = 0;
    if (dmsaa_begin_frame(msaa, &fbo) != DMSAA_STATUS_OK)
        return 0;
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    return 1;
}

static GLuint texture(GLint internal, GLenum format, GLenum type)
{
    GLuint t;
    glGenTextures(1, &t);
    glBindTexture(GL_TEXTURE_2D, t);
    glTexImage2D(GL_TEXTURE_2D, 0, internal, 64, 32, 0, format, type, NULL);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glBindTexture(GL_TEXTURE_2D, 0);
    return t;
}

int main(void)
{
    if (!create_context())
        return 3;
    const float projection[16] = {1.3f, 0, 0, 0, 0, 2.4f, 0, 0, 0, 0, -1.002f, -1, 0, 0, -0.2002f, 0};
    const float orthographic[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1};

    /* a G-buffer with depth, and one without */
    GLuint colour = texture(GL_RGBA16F, GL_RGBA, GL_FLOAT);
    GLuint depth = texture(GL_DEPTH_COMPONENT24, GL_DEPTH_COMPONENT, GL_UNSIGNED_INT);
    GLuint bare = texture(GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE);
    GLuint gbuffer, no_depth;
    glGenFramebuffers(1, &gbuffer);
    glBindFramebuffer(GL_FRAMEBUFFER, gbuffer);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, colour, 0);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, depth, 0);
    glGenFramebuffers(1, &no_depth);
    glBindFramebuffer(GL_FRAMEBUFFER, no_depth);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, bare, 0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);

    DmsaaOptions options = dmsaa_options_default();
    DmsaaRetrofit *msaa = (DmsaaRetrofit *)&options; /* must be overwritten with null */
    uint32_t fbo = 0;
    bool run_lighting = true;

    /* the list */
    expect(dmsaa_retrofit_new(load_gl, NULL, gbuffer, NULL, &msaa), DMSAA_STATUS_NULL_POINTER,
           "null options");
    if (msaa != NULL) {
        fprintf(stderr, "FAIL: a failed dmsaa_retrofit_new left *out non-null\n");
        failures++;
    }
    expect(dmsaa_resolve(NULL, projection, NULL), DMSAA_STATUS_NULL_POINTER, "null handle (resolve)");
    expect(dmsaa_framebuffer(NULL, &fbo), DMSAA_STATUS_NULL_POINTER, "null handle (framebuffer)");
    uint32_t selection = 7;
    expect(dmsaa_second_layer_selection(NULL, &selection), DMSAA_STATUS_NULL_POINTER,
           "null handle (second_layer_selection)");
    expect(dmsaa_begin_second_layer(NULL, 0, &run_lighting), DMSAA_STATUS_NULL_POINTER,
           "null handle (begin_second_layer)");
    if (run_lighting) {
        fprintf(stderr, "FAIL: a failed dmsaa_begin_second_layer left *run_lighting true\n");
        failures++;
    }
    expect(dmsaa_finish_second_layer(NULL, 0), DMSAA_STATUS_NULL_POINTER,
           "null handle (finish_second_layer)");
    expect(dmsaa_set_options(NULL, &options), DMSAA_STATUS_NULL_POINTER, "null handle (set_options)");
    expect(dmsaa_refresh(NULL), DMSAA_STATUS_NULL_POINTER, "null handle (refresh)");
    expect(dmsaa_refresh_with(NULL, gbuffer), DMSAA_STATUS_NULL_POINTER,
           "null handle (refresh_with)");
    dmsaa_destroy(NULL); /* accepted: does nothing */
    expect(dmsaa_retrofit_new(load_gl, NULL, 0, &options, &msaa), DMSAA_STATUS_INVALID_ARGUMENT,
           "zero FBO");
    expect(dmsaa_retrofit_new(load_gl, NULL, no_depth, &options, &msaa),
           DMSAA_STATUS_UNSUITABLE_FRAMEBUFFER, "FBO without depth");
    if (!strstr(dmsaa_last_error(), "GL_DEPTH_ATTACHMENT")) {
        fprintf(stderr, "FAIL: the message for an FBO without depth names no attachment\n");
        failures++;
    }

    /* more null pointers */
    expect(dmsaa_retrofit_new(NULL, NULL, gbuffer, &options, &msaa), DMSAA_STATUS_NULL_POINTER,
           "null loader");
    expect(dmsaa_retrofit_new(load_gl, NULL, gbuffer, &options, NULL), DMSAA_STATUS_NULL_POINTER,
           "null out");

    /* options out of range */
    DmsaaOptions bad = options;
    bad.samples = 0;
    expect(dmsaa_retrofit_new(load_gl, NULL, gbuffer, &bad, &msaa), DMSAA_STATUS_INVALID_ARGUMENT,
           "samples 0");
    bad = options;
    bad.layers = 3;
    expect(dmsaa_retrofit_new(load_gl, NULL, gbuffer, &bad, &msaa), DMSAA_STATUS_INVALID_ARGUMENT,
           "layers 3");
    bad = options;
    bad.method = 9;
    expect(dmsaa_retrofit_new(load_gl, NULL, gbuffer, &bad, &msaa), DMSAA_STATUS_INVALID_ARGUMENT,
           "method 9");
    bad = options;
    bad.fast_path = 2;
    expect(dmsaa_retrofit_new(load_gl, NULL, gbuffer, &bad, &msaa), DMSAA_STATUS_INVALID_ARGUMENT,
           "flag 2");
    bad = options;
    bad.window_c_in = bad.window_c;
    expect(dmsaa_retrofit_new(load_gl, NULL, gbuffer, &bad, &msaa), DMSAA_STATUS_INVALID_ARGUMENT,
           "window_c_in not below window_c");
    bad = options;
    bad.position_attachment = -5;
    expect(dmsaa_retrofit_new(load_gl, NULL, gbuffer, &bad, &msaa), DMSAA_STATUS_INVALID_ARGUMENT,
           "position_attachment -5");
    bad = options;
    bad.position_attachment = 3;
    expect(dmsaa_retrofit_new(load_gl, NULL, gbuffer, &bad, &msaa),
           DMSAA_STATUS_UNSUITABLE_FRAMEBUFFER, "position_attachment with nothing attached");
    bad = options;
    bad.layer_mix = DMSAA_LAYER_MIX_CURVE;
    expect(dmsaa_retrofit_new(load_gl, NULL, gbuffer, &bad, &msaa), DMSAA_STATUS_NULL_POINTER,
           "curve mix without its text");
    /* a loader without one function, a name that is no framebuffer */
    expect(dmsaa_retrofit_new(load_without, (void *)"glGetBooleani_v", gbuffer, &options, &msaa),
           DMSAA_STATUS_UNSUPPORTED, "loader without glGetBooleani_v");
    expect_message("glGetBooleani_v", "a loader without glGetBooleani_v");
    expect(dmsaa_retrofit_new(load_gl, NULL, 9999, &options, &msaa),
           DMSAA_STATUS_INVALID_ARGUMENT, "a name that is no framebuffer");
    expect_message("is not a framebuffer object", "a name that is no framebuffer");
    if (dmsaa_live_objects() != 0) {
        fprintf(stderr, "FAIL: failed dmsaa_retrofit_new calls left %lld GL objects\n",
                (long long)dmsaa_live_objects());
        failures++;
    }

    /* calls out of order, on a valid two-layer retrofit */
    DmsaaOptions two = options;
    two.layers = 2;
    if (dmsaa_retrofit_new(load_gl, NULL, gbuffer, &two, &msaa) != DMSAA_STATUS_OK) {
        fprintf(stderr, "FAIL: a valid dmsaa_retrofit_new failed: %s\n", dmsaa_last_error());
        return 1;
    }
    expect(dmsaa_finish_second_layer(msaa, 0), DMSAA_STATUS_OUT_OF_ORDER, "finish without begin");
    expect(dmsaa_begin_second_layer(msaa, 0, &run_lighting), DMSAA_STATUS_OUT_OF_ORDER,
           "begin before resolve");
    expect(dmsaa_resolve(msaa, orthographic, NULL), DMSAA_STATUS_INVALID_ARGUMENT,
           "orthographic projection");
    expect(dmsaa_resolve(msaa, NULL, NULL), DMSAA_STATUS_NULL_POINTER, "null projection");
    bad = two;
    bad.window = 7;
    expect(dmsaa_set_options(msaa, &bad), DMSAA_STATUS_INVALID_ARGUMENT, "set_options window 7");
    expect(dmsaa_framebuffer(msaa, NULL), DMSAA_STATUS_NULL_POINTER, "null out_fbo");
    expect(dmsaa_second_layer_selection(msaa, NULL), DMSAA_STATUS_NULL_POINTER,
           "null out_texture");

    /* a frame not begun, and one begun but never cleared */
    expect(dmsaa_resolve(msaa, projection, NULL), DMSAA_STATUS_OUT_OF_ORDER,
           "resolve without begin_frame");
    expect_message("begin_frame", "resolve without begin_frame");
    uint32_t twin = 0;
    if (dmsaa_begin_frame(msaa, &twin) != DMSAA_STATUS_OK) {
        fprintf(stderr, "FAIL: begin_frame: %s\n", dmsaa_last_error());
        failures++;
    }
    expect(dmsaa_resolve(msaa, projection, NULL), DMSAA_STATUS_TWINS_NOT_CLEARED,
           "resolve of twins nothing cleared");
    expect_message("clear_twins", "resolve of twins nothing cleared");

    /* the process keeps running and the retrofit keeps working */
    if (!begin_cleared(msaa) || dmsaa_resolve(msaa, projection, NULL) != DMSAA_STATUS_OK) {
        fprintf(stderr, "FAIL: resolve after the bad calls: %s\n", dmsaa_last_error());
        failures++;
    }
    GLuint output;
    GLuint lit = texture(GL_RGBA8, GL_RGBA, GL_UNSIGNED_BYTE);
    glGenFramebuffers(1, &output);
    glBindFramebuffer(GL_FRAMEBUFFER, output);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, lit, 0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    if (dmsaa_begin_second_layer(msaa, output, &run_lighting) != DMSAA_STATUS_OK || !run_lighting) {
        fprintf(stderr, "FAIL: begin after a resolve: %s\n", dmsaa_last_error());
        failures++;
    }
    expect(dmsaa_begin_second_layer(msaa, output, &run_lighting), DMSAA_STATUS_OUT_OF_ORDER,
           "begin twice");
    expect(dmsaa_resolve(msaa, projection, NULL), DMSAA_STATUS_OUT_OF_ORDER,
           "resolve between begin and finish");
    if (dmsaa_finish_second_layer(msaa, output) != DMSAA_STATUS_OK) {
        fprintf(stderr, "FAIL: finish after begin: %s\n", dmsaa_last_error());
        failures++;
    }
    expect(dmsaa_finish_second_layer(msaa, output), DMSAA_STATUS_OUT_OF_ORDER, "finish twice");
    /* a G-buffer made anew under another name: refresh_with takes it, not 0
       nor a name that is no framebuffer, and the handle keeps working */
    expect(dmsaa_refresh_with(msaa, 0), DMSAA_STATUS_INVALID_ARGUMENT, "refresh_with 0");
    expect(dmsaa_refresh_with(msaa, 9999), DMSAA_STATUS_INVALID_ARGUMENT,
           "refresh_with a name that is no framebuffer");
    if (dmsaa_refresh_with(msaa, gbuffer) != DMSAA_STATUS_OK || !begin_cleared(msaa) ||
        dmsaa_resolve(msaa, projection, NULL) != DMSAA_STATUS_OK) {
        fprintf(stderr, "FAIL: refresh_with the G-buffer, then resolve: %s\n", dmsaa_last_error());
        failures++;
    }
    dmsaa_destroy(msaa);

    /* world-space positions need the view matrix */
    DmsaaOptions world = options;
    world.position_attachment = 0;
    world.world_space_position = 1;
    if (dmsaa_retrofit_new(load_gl, NULL, gbuffer, &world, &msaa) != DMSAA_STATUS_OK) {
        fprintf(stderr, "FAIL: a world-space retrofit failed: %s\n", dmsaa_last_error());
        return 1;
    }
    /* one layer: no selection, and that is no error */
    if (dmsaa_second_layer_selection(msaa, &selection) != DMSAA_STATUS_OK || selection != 0) {
        fprintf(stderr, "FAIL: one layer, yet a selection texture %u (%s)\n", selection,
                dmsaa_last_error());
        failures++;
    }
    expect(dmsaa_resolve(msaa, projection, NULL), DMSAA_STATUS_NULL_POINTER,
           "world-space positions without a view");
    dmsaa_destroy(msaa);

    if (dmsaa_live_objects() != 0) {
        fprintf(stderr, "FAIL: %lld GL objects left\n", (long long)dmsaa_live_objects());
        failures++;
    }
    GLenum error = glGetError();
    if (error != GL_NO_ERROR) {
        fprintf(stderr, "FAIL: GL error 0x%04x after the bad calls\n", error);
        failures++;
    }
    GLuint framebuffers[3] = {gbuffer, no_depth, output};
    glDeleteFramebuffers(3, framebuffers);
    GLuint textures[4] = {colour, depth, bare, lit};
    glDeleteTextures(4, textures);
    destroy_context();
    printf("%d bad calls, each an error status with a one-line message\n", bad_calls);
    if (failures) {
        fprintf(stderr, "%d check(s) failed\n", failures);
        return 1;
    }
    printf("ok\n");
    return 0;
}
