/*
 * The least a host outside the repository writes, built with nothing but
 * the installed header and library (`pkg-config --cflags --libs
 * deferred-msaa`): a tutorial-style G-buffer (RGBA16F position and normal,
 * unsized GL_RGBA albedo, a GL_DEPTH_COMPONENT renderbuffer, three draw
 * buffers) retrofitted through dmsaa_options_default, dmsaa_retrofit_new,
 * dmsaa_begin_frame, dmsaa_resolve and dmsaa_destroy. A clear of the
 * multisampled framebuffer stands for the geometry pass; the resolve must
 * then have written the clear colour into the host's own albedo texture.
 *
 * Usage: minimal_host
 */
#include <deferred_msaa.h>

#include "egl_gl.h"

static GLuint attach(GLint internal, GLenum type, GLenum attachment)
{
    GLuint t;
    glGenTextures(1, &t);
    glBindTexture(GL_TEXTURE_2D, t);
    glTexImage2D(GL_TEXTURE_2D, 0, internal, 64, 36, 0, GL_RGBA, type, NULL);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glFramebufferTexture2D(GL_FRAMEBUFFER, attachment, GL_TEXTURE_2D, t, 0);
    return t;
}

int main(void)
{
    if (!create_context())
        return 3;
    GLuint gBuffer, rboDepth, textures[3];
    glGenFramebuffers(1, &gBuffer);
    glBindFramebuffer(GL_FRAMEBUFFER, gBuffer);
    textures[0] = attach(GL_RGBA16F, GL_FLOAT, GL_COLOR_ATTACHMENT0);
    textures[1] = attach(GL_RGBA16F, GL_FLOAT, GL_COLOR_ATTACHMENT1);
    textures[2] = attach(GL_RGBA, GL_UNSIGNED_BYTE, GL_COLOR_ATTACHMENT2);
    unsigned int attachments[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
    glDrawBuffers(3, attachments);
    glGenRenderbuffers(1, &rboDepth);
    glBindRenderbuffer(GL_RENDERBUFFER, rboDepth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT, 64, 36);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rboDepth);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);

    DmsaaOptions options = dmsaa_options_default();
    DmsaaRetrofit *msaa = NULL;
    if (dmsaa_retrofit_new(load_gl, NULL, gBuffer, &options, &msaa) != DMSAA_STATUS_OK) {
        fprintf(stderr, "FAIL: dmsaa_retrofit_new: %s\n", dmsaa_last_error());
        return 1;
    }
    uint32_t fbo = 0;
    if (dmsaa_begin_frame(msaa, &fbo) != DMSAA_STATUS_OK || fbo == 0) {
        fprintf(stderr, "FAIL: dmsaa_begin_frame: %s\n", dmsaa_last_error());
        return 1;
    }
    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glViewport(0, 0, 64, 36);
    glClearColor(0.25f, 0.5f, 0.75f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    const float projection[16] = {1.3f, 0, 0, 0, 0, 2.4f, 0, 0, 0, 0, -1.002f, -1, 0, 0, -0.2002f, 0};
    if (dmsaa_resolve(msaa, projection, NULL) != DMSAA_STATUS_OK) {
        fprintf(stderr, "FAIL: dmsaa_resolve: %s\n", dmsaa_last_error());
        return 1;
    }
    unsigned char texel[4] = {0, 0, 0, 0};
    glBindFramebuffer(GL_READ_FRAMEBUFFER, gBuffer);
    glReadBuffer(GL_COLOR_ATTACHMENT2);
    glReadPixels(10, 10, 1, 1, GL_RGBA, GL_UNSIGNED_BYTE, texel);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    dmsaa_destroy(msaa);
    /* 0.25, 0.5, 0.75, 1 in 8 bits, within the driver's rounding */
    const int expected[4] = {64, 128, 191, 255};
    int ok = 1;
    for (int i = 0; i < 4; i++)
        ok = ok && abs((int)texel[i] - expected[i]) <= 1;
    printf("albedo after the resolve: %u %u %u %u\n", texel[0], texel[1], texel[2], texel[3]);
    glDeleteTextures(3, textures);
    glDeleteRenderbuffers(1, &rboDepth);
    glDeleteFramebuffers(1, &gBuffer);
    destroy_context();
    if (!ok || dmsaa_live_objects() != 0) {
        fprintf(stderr, "FAIL: the resolve did not write the host's albedo, or objects are left\n");
        return 1;
    }
    printf("ok\n");
    return 0;
}
