/*
 * The C engine of engine.h retrofitted in its source, as docs/hosts.md says
 * for its style: two layers with every attachment kept (the octahedral
 * normals and the packed byte selected, the normals named for the
 * clusters), the radiance's tonemap declared (DMSAA_LAYER_MIX_CURVE:
 * exposure, then clamp; with nothing declared the library cannot tell it
 * and refuses), its clear values declared and the frame begun with
 * dmsaa_begin_frame.
 *
 * Writes raw RGBA8 images (rows bottom-up) into OUT_DIR: none.rgba,
 * msaa.rgba (one layer), layers.rgba (two layers, the tonemap declared),
 * layers-linear.rgba, layers-tonemapped.rgba, layers-srgb.rgba (two
 * layers, each other declaration), layers-auto.rgba (nothing declared:
 * refused, so the one-layer frame), reference.rgba (the
 * engine at 4x the width and height, averaged 4x4 in linear light), and
 * edges.mask (one byte a pixel, 255 where the engine's own frame has a
 * depth or normal edge). Exits non-zero with a line saying why on any
 * failed check.
 *
 * Usage: engine_host OUT_DIR
 */
#include "engine_retrofit.h"

/* With `mix` DMSAA_LAYER_MIX_AUTO and two layers, the library cannot
 * infer the RGBA16F radiance's domain: dmsaa_begin_second_layer must
 * refuse with DMSAA_STATUS_LAYER_MIX_UNDECLARED, having done nothing (the
 * frame is the one-layer frame), and the message must name the
 * declarations. */
static void retrofitted_frame(Engine *e, uint32_t layers, DmsaaLayerMix mix, const char *dir, const char *name)
{
    DmsaaOptions options = engine_options(layers, mix);
    bool refused = layers == 2 && mix == DMSAA_LAYER_MIX_AUTO;
    DmsaaRetrofit *msaa = NULL;
    if (!ok(dmsaa_retrofit_new(load_gl, NULL, e->gbuffer, &options, &msaa), "dmsaa_retrofit_new"))
        return;
    for (int frame = 0; frame < 2; frame++) {
        clear_gbuffer(e);
        GLuint fbo = 0;
        ok(dmsaa_begin_frame(msaa, &fbo), "dmsaa_begin_frame");
        geometry_pass(e, fbo);
        ok(dmsaa_resolve(msaa, e->projection, NULL), "dmsaa_resolve");
        lighting_pass(e);
        bool run = false;
        if (refused) {
            DmsaaStatus status = dmsaa_begin_second_layer(msaa, e->hdr_fbo, &run);
            const char *message = status == DMSAA_STATUS_OK ? "" : dmsaa_last_error();
            if (frame == 0)
                printf("layer_mix auto into RGBA16F: status %d: %s\n", (int)status, message);
            CHECK(status == DMSAA_STATUS_LAYER_MIX_UNDECLARED && !run,
                  "%s: two layers, nothing declared, into RGBA16F: status %d, run_lighting %d", name, (int)status,
                  run);
            CHECK(strstr(message, "DMSAA_LAYER_MIX_CURVE") && strstr(message, "DMSAA_LAYER_MIX_TONEMAPPED") &&
                      strstr(message, "DMSAA_LAYER_MIX_LINEAR"),
                  "%s: the refusal does not name the declarations: %s", name, message);
        } else {
            ok(dmsaa_begin_second_layer(msaa, e->hdr_fbo, &run), "dmsaa_begin_second_layer");
            CHECK(run == (layers == 2), "%s: run_lighting %d with %u layers", name, run, layers);
        }
        if (run) {
            lighting_pass(e);
            ok(dmsaa_finish_second_layer(msaa, e->hdr_fbo), "dmsaa_finish_second_layer");
        }
        tonemap_pass(e);
    }
    gl_errors(name);
    write_screen(e, dir, name);
    dmsaa_destroy(msaa);
    CHECK(dmsaa_live_objects() == 0, "%lld objects of the library left", (long long)dmsaa_live_objects());
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
        version_line = "#version 150 core\n#extension GL_ARB_explicit_attrib_location : require\n";
    GLint draw_buffers = 0;
    glGetIntegerv(GL_MAX_DRAW_BUFFERS, &draw_buffers);
    printf("GL %s, %d draw buffers\n", (const char *)glGetString(GL_VERSION), draw_buffers);
    printf("image %dx%d\n", WIDTH, HEIGHT);

    Engine e;
    engine_init(&e, WIDTH, HEIGHT);
    clear_gbuffer(&e);
    geometry_pass(&e, e.gbuffer);
    lighting_pass(&e);
    tonemap_pass(&e);
    gl_errors("the engine's own frame");
    write_screen(&e, dir, "none.rgba");
    write_edges(&e, dir);
    retrofitted_frame(&e, 1, DMSAA_LAYER_MIX_CURVE, dir, "msaa.rgba");
    retrofitted_frame(&e, 2, DMSAA_LAYER_MIX_CURVE, dir, "layers.rgba");
    /* The other declarations, and none, for the test to measure. */
    retrofitted_frame(&e, 2, DMSAA_LAYER_MIX_LINEAR, dir, "layers-linear.rgba");
    retrofitted_frame(&e, 2, DMSAA_LAYER_MIX_TONEMAPPED, dir, "layers-tonemapped.rgba");
    retrofitted_frame(&e, 2, DMSAA_LAYER_MIX_SRGB_ENCODED, dir, "layers-srgb.rgba");
    retrofitted_frame(&e, 2, DMSAA_LAYER_MIX_AUTO, dir, "layers-auto.rgba");
    engine_free(&e);
    write_reference(dir);
    gl_errors("the supersampled frame");
    destroy_context();
    if (failures) {
        fprintf(stderr, "%d check(s) failed\n", failures);
        return 1;
    }
    printf("ok\n");
    return 0;
}
