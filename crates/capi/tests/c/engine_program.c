/*
 * The C engine of engine.h as a program: its render loop on a surfaceless
 * EGL context (no window, no swap), FRAMES frames into its screen target,
 * the last one read back and written to OUT_FILE (raw RGBA8, rows
 * bottom-up). Built twice from this source:
 *
 * - as it is: no line of the retrofit, not linked with the library. This
 *   is what `deferred-msaa inject` is run on;
 * - with -DDMSAA_IN_SOURCE: the retrofit in its source, as inject applies
 *   it with the profile docs/inject.md's engine example gives (the
 *   options of engine_retrofit.h at two layers): each frame begun after the
 *   engine's clear, the resolve after the geometry, the lighting drawn again
 *   into dmsaa_begin_second_layer_own_target's framebuffer and mixed into
 *   the radiance target before the tonemap.
 *
 * Usage: engine_program OUT_FILE [--frames N] [--reference DIR] [--shadow-block] [--orphan-camera]
 *                       [--depth-tested-lighting] [--mapped-camera] [--forward-renderer]
 *                       [--two-gbuffers] [--osmesa]
 *   --reference DIR  also writes the engine's 16x image (reference.rgba:
 *                    4x the width and height, averaged 4x4 in linear light)
 *                    and its edges (edges.mask) into DIR
 *   --shadow-block   a second camera block (binding 1), a spot light's
 *                    projection and view written into it each frame, as an
 *                    engine keeps its shadow cameras (no pass reads it here)
 *   --orphan-camera  the camera block given new storage with its values each
 *                    frame (glBufferData), as engines orphan a buffer
 *   --depth-tested-lighting  the radiance framebuffer shares the G-buffer's
 *                    depth, and the lighting is two quads at the far plane
 *                    tested against it (GL_GREATER: geometry; GL_LEQUAL:
 *                    sky), as engines light
 *   --mapped-camera  the camera block written through glMapBufferRange
 *   --forward-renderer  no G-buffer: the cubes drawn straight into the
 *                    screen target, unlit (a forward renderer)
 *   --two-gbuffers   a second engine (a mirror's view, say) with a G-buffer
 *                    of the same shape, drawn and lit each frame too
 *   --osmesa         the context made by Mesa's off-screen renderer (dlopened
 *                    libOSMesa, entry points from OSMesaGetProcAddress)
 *
 * Prints "ok" last, or exits non-zero with a line saying why.
 */
#ifdef DMSAA_IN_SOURCE
#include "engine_retrofit.h"
#else
#include "engine.h"
#endif

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: %s OUT_FILE [--frames N] [--reference DIR]\n", argv[0]);
        return 2;
    }
    const char *out = argv[1];
    const char *reference = NULL;
    int frames = 3;
    int shadow_block = 0, forward_renderer = 0, two_gbuffers = 0, osmesa = 0;
    for (int i = 2; i < argc; i++) {
        if (strcmp(argv[i], "--frames") == 0 && i + 1 < argc) {
            frames = atoi(argv[++i]);
        } else if (strcmp(argv[i], "--reference") == 0 && i + 1 < argc) {
            reference = argv[++i];
        } else if (strcmp(argv[i], "--shadow-block") == 0) {
            shadow_block = 1;
        } else if (strcmp(argv[i], "--orphan-camera") == 0) {
            camera_orphaned = 1;
        } else if (strcmp(argv[i], "--depth-tested-lighting") == 0) {
            depth_tested_lighting = 1;
        } else if (strcmp(argv[i], "--mapped-camera") == 0) {
            camera_mapped = 1;
        } else if (strcmp(argv[i], "--forward-renderer") == 0) {
            forward_renderer = 1;
        } else if (strcmp(argv[i], "--two-gbuffers") == 0) {
            two_gbuffers = 1;
        } else if (strcmp(argv[i], "--osmesa") == 0) {
            osmesa = 1;
        } else {
            fprintf(stderr, "unknown argument %s\n", argv[i]);
            return 2;
        }
    }
    if (frames < 1) {
        fprintf(stderr, "--frames needs 1 or more\n");
        return 2;
    }
    static unsigned char osmesa_buffer[WIDTH * HEIGHT * 4];
    if (osmesa ? !create_osmesa_context(osmesa_buffer, WIDTH, HEIGHT) : !create_context())
        return 3;
    GLint major = 0, minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    if (major * 10 + minor < 33)
        version_line = "#version 150 core\n#extension GL_ARB_explicit_attrib_location : require\n";
    printf("GL %s through EGL\n", (const char *)glGetString(GL_VERSION));

    Engine e;
    engine_init(&e, WIDTH, HEIGHT);
#ifdef DMSAA_IN_SOURCE
    DmsaaOptions options = engine_options(2, DMSAA_LAYER_MIX_CURVE);
    DmsaaRetrofit *msaa = NULL;
    if (!ok(dmsaa_retrofit_new(load_gl, NULL, e.gbuffer, &options, &msaa), "dmsaa_retrofit_new"))
        return 1;
#endif
    Engine mirror;
    if (two_gbuffers)
        engine_init(&mirror, WIDTH, HEIGHT);
    GLuint shadow_ubo = 0;
    float shadow[32];
    if (shadow_block) {
        /* a spot light's camera: 60 degrees, square, looking down at the grid */
        float f = 1.0f / tanf(0.5236f), near = 0.5f, far = 40.0f;
        memset(shadow, 0, sizeof shadow);
        shadow[0] = f, shadow[5] = f;
        shadow[10] = (far + near) / (near - far), shadow[11] = -1.0f;
        shadow[14] = 2.0f * far * near / (near - far);
        identity(shadow + 16);
        shadow[16 + 5] = 0.0f, shadow[16 + 6] = -1.0f, shadow[16 + 9] = 1.0f, shadow[16 + 10] = 0.0f;
        shadow[16 + 14] = -12.0f;
        glGenBuffers(1, &shadow_ubo);
        glBindBuffer(GL_UNIFORM_BUFFER, shadow_ubo);
        glBufferData(GL_UNIFORM_BUFFER, sizeof shadow, NULL, GL_DYNAMIC_DRAW);
        glBindBuffer(GL_UNIFORM_BUFFER, 0);
        glBindBufferBase(GL_UNIFORM_BUFFER, 1, shadow_ubo);
    }
    for (int frame = 0; frame < frames; frame++) {
        if (shadow_block) {
            glBindBuffer(GL_UNIFORM_BUFFER, shadow_ubo);
            glBufferSubData(GL_UNIFORM_BUFFER, 0, sizeof shadow, shadow);
            glBindBuffer(GL_UNIFORM_BUFFER, 0);
        }
        if (forward_renderer) {
            /* no G-buffer: unlit cubes straight into the screen target */
            static const float black[4] = {0, 0, 0, 1};
            glBindFramebuffer(GL_FRAMEBUFFER, e.screen_fbo);
            glClearBufferfv(GL_COLOR, 0, black);
            geometry_pass(&e, e.screen_fbo);
            gl_errors("a forward frame");
            continue;
        }
        if (two_gbuffers) {
            /* the mirror's view: its own G-buffer of the same shape, lit */
            clear_gbuffer(&mirror);
            geometry_pass(&mirror, mirror.gbuffer);
            lighting_pass(&mirror);
        }
        clear_gbuffer(&e);
#ifdef DMSAA_IN_SOURCE
        GLuint geometry_target = 0;
        ok(dmsaa_begin_frame(msaa, &geometry_target), "dmsaa_begin_frame");
        geometry_pass(&e, geometry_target);
        ok(dmsaa_resolve(msaa, e.projection, NULL), "dmsaa_resolve");
#else
        geometry_pass(&e, e.gbuffer);
#endif
        lighting_pass(&e);
#ifdef DMSAA_IN_SOURCE
        GLuint own = 0;
        if (ok(dmsaa_begin_second_layer_own_target(msaa, e.hdr_fbo, &own), "dmsaa_begin_second_layer_own_target")) {
            lighting_into(&e, own);
            ok(dmsaa_finish_second_layer(msaa, e.hdr_fbo), "dmsaa_finish_second_layer");
        }
#endif
        tonemap_pass(&e);
        gl_errors("a frame");
    }
    write_screen(&e, NULL, out);
    if (reference) {
        write_edges(&e, reference);
        write_reference(reference);
    }
#ifdef DMSAA_IN_SOURCE
    dmsaa_destroy(msaa);
#endif
    if (shadow_ubo)
        glDeleteBuffers(1, &shadow_ubo);
    if (two_gbuffers)
        engine_free(&mirror);
    engine_free(&e);
    gl_errors("the end");
    destroy_context();
    if (failures) {
        fprintf(stderr, "%d check(s) failed\n", failures);
        return 1;
    }
    printf("ok\n");
    return 0;
}
