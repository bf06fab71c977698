/*
 * tutorial_host.c's check of the GL state around every library call: the
 * state a host relies on between its passes, captured before a call and
 * compared after it. Included by tutorial_host.c after its Engine type and
 * its CHECK macro, which it uses.
 */
#ifndef TUTORIAL_HOST_STATE_H
#define TUTORIAL_HOST_STATE_H

/* The GL state a host relies on between its passes. */
typedef struct {
    GLint ints[64];
    GLfloat floats[8];
    int count;
} GlState;

static void capture(const Engine *e, GlState *s)
{
    static const GLenum queried[] = {
        GL_DRAW_FRAMEBUFFER_BINDING, GL_READ_FRAMEBUFFER_BINDING, GL_RENDERBUFFER_BINDING,
        GL_CURRENT_PROGRAM, GL_VERTEX_ARRAY_BINDING, GL_ARRAY_BUFFER_BINDING, GL_ACTIVE_TEXTURE,
        GL_DEPTH_FUNC, GL_DEPTH_WRITEMASK, GL_BLEND_SRC_RGB, GL_BLEND_DST_RGB, GL_BLEND_SRC_ALPHA,
        GL_BLEND_DST_ALPHA, GL_STENCIL_FUNC, GL_STENCIL_REF, GL_STENCIL_VALUE_MASK,
        GL_STENCIL_WRITEMASK, GL_STENCIL_FAIL, GL_STENCIL_PASS_DEPTH_PASS, GL_UNPACK_ALIGNMENT,
        GL_PACK_ALIGNMENT, GL_READ_BUFFER, GL_DRAW_BUFFER0, GL_DRAW_BUFFER1, GL_DRAW_BUFFER2,
        GL_CULL_FACE_MODE, GL_FRONT_FACE,
    };
    static const GLenum enables[] = {GL_DEPTH_TEST, GL_BLEND, GL_CULL_FACE, GL_STENCIL_TEST,
                                     GL_SCISSOR_TEST, GL_MULTISAMPLE, GL_FRAMEBUFFER_SRGB};
    int n = 0;
    for (size_t i = 0; i < sizeof queried / sizeof queried[0]; i++)
        glGetIntegerv(queried[i], &s->ints[n++]);
    for (size_t i = 0; i < sizeof enables / sizeof enables[0]; i++)
        s->ints[n++] = glIsEnabled(enables[i]);
    glGetIntegerv(GL_VIEWPORT, &s->ints[n]);
    n += 4;
    glGetIntegerv(GL_SCISSOR_BOX, &s->ints[n]);
    n += 4;
    GLboolean mask[4];
    glGetBooleanv(GL_COLOR_WRITEMASK, mask);
    for (int i = 0; i < 4; i++)
        s->ints[n++] = mask[i];
    /* the texture bound on each unit the lighting uses, then the unit back */
    GLint active;
    glGetIntegerv(GL_ACTIVE_TEXTURE, &active);
    for (int unit = 0; unit < 4; unit++) {
        glActiveTexture(GL_TEXTURE0 + unit);
        glGetIntegerv(GL_TEXTURE_BINDING_2D, &s->ints[n++]);
    }
    glActiveTexture(active);
    /* the G-buffer's own draw buffers, then the binding back */
    GLint draw;
    glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &draw);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, e->gBuffer);
    for (int i = 0; i < 3; i++)
        glGetIntegerv(GL_DRAW_BUFFER0 + i, &s->ints[n++]);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, draw);
    s->count = n;
    glGetFloatv(GL_COLOR_CLEAR_VALUE, s->floats);
    glGetFloatv(GL_DEPTH_CLEAR_VALUE, &s->floats[4]);
}

static int state_checks = 0;

static void check_state(const Engine *e, const GlState *before, const char *call)
{
    GlState after;
    capture(e, &after);
    state_checks++;
    for (int i = 0; i < before->count; i++)
        CHECK(before->ints[i] == after.ints[i], "GL state item %d changed across %s: %d -> %d", i,
              call, before->ints[i], after.ints[i]);
    for (int i = 0; i < 5; i++)
        CHECK(before->floats[i] == after.floats[i], "clear value %d changed across %s", i, call);
}

#endif
