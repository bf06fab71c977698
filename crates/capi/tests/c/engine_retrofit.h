/*
 * The C engine's retrofit, shared by its in-source programs
 * (engine_host.c, and engine_program.c built with DMSAA_IN_SOURCE): the
 * options docs/hosts.md gives its style, and the status check.
 */
#ifndef DMSAA_TEST_ENGINE_RETROFIT_H
#define DMSAA_TEST_ENGINE_RETROFIT_H

#include "deferred_msaa.h"
#include "engine.h"

static int ok(DmsaaStatus status, const char *call)
{
    if (status != DMSAA_STATUS_OK) {
        fprintf(stderr, "%s: status %d: %s\n", call, (int)status, dmsaa_last_error());
        failures++;
        return 0;
    }
    return 1;
}

/* The options docs/hosts.md gives this engine's style. */
static DmsaaOptions engine_options(uint32_t layers, DmsaaLayerMix mix)
{
    DmsaaOptions o = dmsaa_options_default();
    o.layers = layers;
    o.normal_attachment = 1;
    o.normal_encoding = DMSAA_NORMAL_OCTAHEDRAL_UNORM;
    o.rules[1] = DMSAA_RULE_SELECT; /* octahedral encodings do not blend */
    o.rules[2] = DMSAA_RULE_SELECT;
    o.rules[3] = DMSAA_RULE_SELECT; /* a packed byte: its bits do not blend */
    /* radiance, and the engine's tonemap: linear, then clamped. The mix
     * is in its domain (what reaches the screen), mapped back. */
    o.layer_mix = DMSAA_LAYER_MIX_CURVE;
    o.layer_mix_curve = "vec3 dmsaa_curve(vec3 x) { return clamp(x * 0.8, 0.0, 1.0); }\n"
                        "vec3 dmsaa_curve_inverse(vec3 y) { return y / 0.8; }\n";
    /* The test's other declarations (and none), to measure against. */
    if (mix != DMSAA_LAYER_MIX_CURVE) {
        o.layer_mix = mix;
        o.layer_mix_curve = NULL;
    }
    o.clear_twins = 1;
    o.clear_colors[1][0] = o.clear_colors[1][1] = 0.5f;
    o.clear_colors[2][0] = o.clear_colors[2][1] = 0.5f;
    o.clear_colors[3][1] = o.clear_colors[3][3] = 1.0f;
    o.clear_colors[4][0] = FAR_DEPTH;
    o.clear_depth = 1.0f;
    o.clear_stencil = 0;
    return o;
}

#endif
