// The tutorial program's G-buffer made through direct state access (GL
// 4.5), as engines on 4.5 make theirs: inject_tutorial.cpp's --dsa. After
// tutorial_program.hpp (the Engine it remakes, the loader's names).
#ifndef TUTORIAL_DSA_HPP
#define TUTORIAL_DSA_HPP

// The direct-state-access functions of --dsa (GL 4.5), loaded by name.
static PFNGLCREATEFRAMEBUFFERSPROC dsaCreateFramebuffers;
static PFNGLCREATETEXTURESPROC dsaCreateTextures;
static PFNGLTEXTURESTORAGE2DPROC dsaTextureStorage2D;
static PFNGLTEXTUREPARAMETERIPROC dsaTextureParameteri;
static PFNGLCREATERENDERBUFFERSPROC dsaCreateRenderbuffers;
static PFNGLNAMEDRENDERBUFFERSTORAGEPROC dsaNamedRenderbufferStorage;
static PFNGLNAMEDFRAMEBUFFERTEXTUREPROC dsaNamedFramebufferTexture;
static PFNGLNAMEDFRAMEBUFFERRENDERBUFFERPROC dsaNamedFramebufferRenderbuffer;
static PFNGLNAMEDFRAMEBUFFERDRAWBUFFERSPROC dsaNamedFramebufferDrawBuffers;
static PFNGLCHECKNAMEDFRAMEBUFFERSTATUSPROC dsaCheckNamedFramebufferStatus;
static PFNGLBLITNAMEDFRAMEBUFFERPROC dsaBlitNamedFramebuffer;

// Whether every --dsa function was found.
static inline bool loadDsa()
{
#define DSA_LOAD(var, type, name)                                                                  \
    var = reinterpret_cast<type>(TUTORIAL_GET_PROC_ADDRESS(name));                                \
    if (!var)                                                                                      \
        return false;
    DSA_LOAD(dsaCreateFramebuffers, PFNGLCREATEFRAMEBUFFERSPROC, "glCreateFramebuffers")
    DSA_LOAD(dsaCreateTextures, PFNGLCREATETEXTURESPROC, "glCreateTextures")
    DSA_LOAD(dsaTextureStorage2D, PFNGLTEXTURESTORAGE2DPROC, "glTextureStorage2D")
    DSA_LOAD(dsaTextureParameteri, PFNGLTEXTUREPARAMETERIPROC, "glTextureParameteri")
    DSA_LOAD(dsaCreateRenderbuffers, PFNGLCREATERENDERBUFFERSPROC, "glCreateRenderbuffers")
    DSA_LOAD(dsaNamedRenderbufferStorage, PFNGLNAMEDRENDERBUFFERSTORAGEPROC, "glNamedRenderbufferStorage")
    DSA_LOAD(dsaNamedFramebufferTexture, PFNGLNAMEDFRAMEBUFFERTEXTUREPROC, "glNamedFramebufferTexture")
    DSA_LOAD(dsaNamedFramebufferRenderbuffer, PFNGLNAMEDFRAMEBUFFERRENDERBUFFERPROC,
             "glNamedFramebufferRenderbuffer")
    DSA_LOAD(dsaNamedFramebufferDrawBuffers, PFNGLNAMEDFRAMEBUFFERDRAWBUFFERSPROC, "glNamedFramebufferDrawBuffers")
    DSA_LOAD(dsaCheckNamedFramebufferStatus, PFNGLCHECKNAMEDFRAMEBUFFERSTATUSPROC, "glCheckNamedFramebufferStatus")
    DSA_LOAD(dsaBlitNamedFramebuffer, PFNGLBLITNAMEDFRAMEBUFFERPROC, "glBlitNamedFramebuffer")
#undef DSA_LOAD
    return true;
}

// The G-buffer made through direct state access at `width` x `height`,
// under a new name: made before the old one (whatever made it) is
// deleted, as an engine swaps in its new render targets.
static inline void makeDsaGBuffer(Engine &e, int width, int height)
{
    GLuint textures[3], depth = 0, framebuffer = 0;
    dsaCreateTextures(GL_TEXTURE_2D, 3, textures);
    const GLenum formats[3] = {GL_RGBA16F, GL_RGBA16F, GL_RGBA8};
    dsaCreateRenderbuffers(1, &depth);
    dsaNamedRenderbufferStorage(depth, GL_DEPTH_COMPONENT24, width, height);
    dsaCreateFramebuffers(1, &framebuffer);
    for (int i = 0; i < 3; i++) {
        dsaTextureStorage2D(textures[i], 1, formats[i], width, height);
        dsaTextureParameteri(textures[i], GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        dsaTextureParameteri(textures[i], GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        dsaNamedFramebufferTexture(framebuffer, GL_COLOR_ATTACHMENT0 + static_cast<GLenum>(i), textures[i], 0);
    }
    dsaNamedFramebufferRenderbuffer(framebuffer, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth);
    const GLenum attachments[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
    dsaNamedFramebufferDrawBuffers(framebuffer, 3, attachments);
    CHECK(dsaCheckNamedFramebufferStatus(framebuffer, GL_DRAW_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE,
          "the G-buffer made by name is incomplete");
    glDeleteFramebuffers(1, &e.gBuffer);
    GLuint old[3] = {e.gPosition, e.gNormal, e.gAlbedoSpec};
    glDeleteTextures(3, old);
    glDeleteRenderbuffers(1, &e.rboDepth);
    e.gBuffer = framebuffer;
    e.gPosition = textures[0];
    e.gNormal = textures[1];
    e.gAlbedoSpec = textures[2];
    e.rboDepth = depth;
    e.width = width;
    e.height = height;
    glViewport(0, 0, width, height);
}

#endif
