/*
 * The C test hosts' window system and GL loader, the way a small C engine
 * without GLAD or GLEW does it: a surfaceless EGL context (Mesa's
 * EGL_PLATFORM_SURFACELESS_MESA, no display server needed) and each GL
 * entry point the host calls looked up once through eglGetProcAddress.
 * Header-only: each test program includes it once.
 */
#ifndef DMSAA_TEST_EGL_GL_H
#define DMSAA_TEST_EGL_GL_H

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/glcorearb.h>
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>

#ifndef EGL_PLATFORM_SURFACELESS_MESA
#define EGL_PLATFORM_SURFACELESS_MESA 0x31DD
#endif

/* The GL entry points the hosts use, as function pointers of the names
 * the tutorial calls (glcorearb.h declares no prototypes without
 * GL_GLCOREARB_PROTOTYPES, so the names are free). */
#define GL_FUNCTIONS(X)                                                        \
    X(PFNGLGETERRORPROC, glGetError)                                           \
    X(PFNGLCLEARBUFFERFVPROC, glClearBufferfv)                                 \
    X(PFNGLCLEARBUFFERFIPROC, glClearBufferfi)                                 \
    X(PFNGLUNIFORM2FPROC, glUniform2f)                                         \
    X(PFNGLSTENCILOPPROC, glStencilOp)                                         \
    X(PFNGLGETSTRINGPROC, glGetString)                                         \
    X(PFNGLGETINTEGERVPROC, glGetIntegerv)                                     \
    X(PFNGLGETINTEGERI_VPROC, glGetIntegeri_v)                                 \
    X(PFNGLGETFLOATVPROC, glGetFloatv)                                         \
    X(PFNGLGETBOOLEANVPROC, glGetBooleanv)                                     \
    X(PFNGLISENABLEDPROC, glIsEnabled)                                         \
    X(PFNGLENABLEPROC, glEnable)                                               \
    X(PFNGLDISABLEPROC, glDisable)                                             \
    X(PFNGLVIEWPORTPROC, glViewport)                                           \
    X(PFNGLCLEARCOLORPROC, glClearColor)                                       \
    X(PFNGLCLEARPROC, glClear)                                                 \
    X(PFNGLDEPTHFUNCPROC, glDepthFunc)                                         \
    X(PFNGLDEPTHMASKPROC, glDepthMask)                                         \
    X(PFNGLBLENDFUNCPROC, glBlendFunc)                                         \
    X(PFNGLSTENCILFUNCPROC, glStencilFunc)                                     \
    X(PFNGLSTENCILMASKPROC, glStencilMask)                                     \
    X(PFNGLPIXELSTOREIPROC, glPixelStorei)                                     \
    X(PFNGLREADPIXELSPROC, glReadPixels)                                       \
    X(PFNGLREADBUFFERPROC, glReadBuffer)                                       \
    X(PFNGLFINISHPROC, glFinish)                                               \
    X(PFNGLGENFRAMEBUFFERSPROC, glGenFramebuffers)                             \
    X(PFNGLBINDFRAMEBUFFERPROC, glBindFramebuffer)                             \
    X(PFNGLDELETEFRAMEBUFFERSPROC, glDeleteFramebuffers)                       \
    X(PFNGLFRAMEBUFFERTEXTURE2DPROC, glFramebufferTexture2D)                   \
    X(PFNGLFRAMEBUFFERRENDERBUFFERPROC, glFramebufferRenderbuffer)             \
    X(PFNGLCHECKFRAMEBUFFERSTATUSPROC, glCheckFramebufferStatus)               \
    X(PFNGLDRAWBUFFERSPROC, glDrawBuffers)                                     \
    X(PFNGLBLITFRAMEBUFFERPROC, glBlitFramebuffer)                             \
    X(PFNGLGENRENDERBUFFERSPROC, glGenRenderbuffers)                           \
    X(PFNGLBINDRENDERBUFFERPROC, glBindRenderbuffer)                           \
    X(PFNGLRENDERBUFFERSTORAGEPROC, glRenderbufferStorage)                     \
    X(PFNGLDELETERENDERBUFFERSPROC, glDeleteRenderbuffers)                     \
    X(PFNGLGENTEXTURESPROC, glGenTextures)                                     \
    X(PFNGLBINDTEXTUREPROC, glBindTexture)                                     \
    X(PFNGLDELETETEXTURESPROC, glDeleteTextures)                               \
    X(PFNGLTEXIMAGE2DPROC, glTexImage2D)                                       \
    X(PFNGLTEXPARAMETERIPROC, glTexParameteri)                                 \
    X(PFNGLACTIVETEXTUREPROC, glActiveTexture)                                 \
    X(PFNGLGENVERTEXARRAYSPROC, glGenVertexArrays)                             \
    X(PFNGLBINDVERTEXARRAYPROC, glBindVertexArray)                             \
    X(PFNGLDELETEVERTEXARRAYSPROC, glDeleteVertexArrays)                       \
    X(PFNGLGENBUFFERSPROC, glGenBuffers)                                       \
    X(PFNGLBINDBUFFERPROC, glBindBuffer)                                       \
    X(PFNGLBUFFERDATAPROC, glBufferData)                                       \
    X(PFNGLBUFFERSUBDATAPROC, glBufferSubData)                                 \
    X(PFNGLMAPBUFFERRANGEPROC, glMapBufferRange)                               \
    X(PFNGLUNMAPBUFFERPROC, glUnmapBuffer)                                     \
    X(PFNGLBINDBUFFERBASEPROC, glBindBufferBase)                               \
    X(PFNGLGETUNIFORMBLOCKINDEXPROC, glGetUniformBlockIndex)                   \
    X(PFNGLUNIFORMBLOCKBINDINGPROC, glUniformBlockBinding)                     \
    X(PFNGLDELETEBUFFERSPROC, glDeleteBuffers)                                 \
    X(PFNGLENABLEVERTEXATTRIBARRAYPROC, glEnableVertexAttribArray)             \
    X(PFNGLVERTEXATTRIBPOINTERPROC, glVertexAttribPointer)                     \
    X(PFNGLDRAWARRAYSPROC, glDrawArrays)                                       \
    X(PFNGLCREATESHADERPROC, glCreateShader)                                   \
    X(PFNGLSHADERSOURCEPROC, glShaderSource)                                   \
    X(PFNGLCOMPILESHADERPROC, glCompileShader)                                 \
    X(PFNGLGETSHADERIVPROC, glGetShaderiv)                                     \
    X(PFNGLGETSHADERINFOLOGPROC, glGetShaderInfoLog)                           \
    X(PFNGLDELETESHADERPROC, glDeleteShader)                                   \
    X(PFNGLCREATEPROGRAMPROC, glCreateProgram)                                 \
    X(PFNGLATTACHSHADERPROC, glAttachShader)                                   \
    X(PFNGLLINKPROGRAMPROC, glLinkProgram)                                     \
    X(PFNGLGETPROGRAMIVPROC, glGetProgramiv)                                   \
    X(PFNGLGETPROGRAMINFOLOGPROC, glGetProgramInfoLog)                         \
    X(PFNGLDELETEPROGRAMPROC, glDeleteProgram)                                 \
    X(PFNGLUSEPROGRAMPROC, glUseProgram)                                       \
    X(PFNGLGETUNIFORMLOCATIONPROC, glGetUniformLocation)                       \
    X(PFNGLUNIFORM1IPROC, glUniform1i)                                         \
    X(PFNGLUNIFORM1FPROC, glUniform1f)                                         \
    X(PFNGLUNIFORM3FPROC, glUniform3f)                                         \
    X(PFNGLUNIFORMMATRIX4FVPROC, glUniformMatrix4fv)                           \
    X(PFNGLISFRAMEBUFFERPROC, glIsFramebuffer)                                 \
    X(PFNGLISTEXTUREPROC, glIsTexture)                                         \
    X(PFNGLISPROGRAMPROC, glIsProgram)

#define GL_DECLARE(type, name) static type name;
GL_FUNCTIONS(GL_DECLARE)
#undef GL_DECLARE

/* The tutorial's windowing library would give these; here EGL does. */
static EGLDisplay egl_display;
static EGLContext egl_context;

/* A GL 3.2 core context current on this thread (Mesa gives its newest
 * core version for any 3.2+ request; the CI's floor pins 3.2), and every
 * entry point above loaded. Returns 0 and prints why on failure. */
static int create_context(void)
{
    PFNEGLGETPLATFORMDISPLAYEXTPROC get_platform_display =
        (PFNEGLGETPLATFORMDISPLAYEXTPROC)eglGetProcAddress("eglGetPlatformDisplayEXT");
    if (!get_platform_display) {
        fprintf(stderr, "no eglGetPlatformDisplayEXT\n");
        return 0;
    }
    egl_display = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, NULL);
    if (egl_display == EGL_NO_DISPLAY || !eglInitialize(egl_display, NULL, NULL)) {
        fprintf(stderr, "no surfaceless EGL display (0x%x)\n", eglGetError());
        return 0;
    }
    if (!eglBindAPI(EGL_OPENGL_API)) {
        fprintf(stderr, "eglBindAPI(EGL_OPENGL_API) failed\n");
        return 0;
    }
    /* EGL_SURFACE_TYPE's default, EGL_WINDOW_BIT, matches nothing on a
     * surfaceless display; 0 matches every config. */
    const EGLint config_attributes[] = {EGL_SURFACE_TYPE, 0, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT,
                                        EGL_NONE};
    EGLConfig config;
    EGLint configs = 0;
    if (!eglChooseConfig(egl_display, config_attributes, &config, 1, &configs) || configs < 1) {
        fprintf(stderr, "no EGL config for desktop OpenGL\n");
        return 0;
    }
    const EGLint context_attributes[] = {
        EGL_CONTEXT_MAJOR_VERSION, 3,
        EGL_CONTEXT_MINOR_VERSION, 2,
        EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
        EGL_NONE,
    };
    egl_context = eglCreateContext(egl_display, config, EGL_NO_CONTEXT, context_attributes);
    if (egl_context == EGL_NO_CONTEXT ||
        !eglMakeCurrent(egl_display, EGL_NO_SURFACE, EGL_NO_SURFACE, egl_context)) {
        fprintf(stderr, "no GL 3.2 core context (0x%x)\n", eglGetError());
        return 0;
    }
#define GL_LOAD(type, name)                                                    \
    name = (type)eglGetProcAddress(#name);                                     \
    if (!name) {                                                               \
        fprintf(stderr, "no GL entry point %s\n", #name);                      \
        return 0;                                                              \
    }
    GL_FUNCTIONS(GL_LOAD)
#undef GL_LOAD
    return 1;
}

/* The same context through Mesa's off-screen renderer instead (a C program
 * with no window system at all): libOSMesa opened with dlopen, a 3.2 core
 * context rendering into `buffer` (width x height RGBA8), every entry point
 * above loaded through OSMesaGetProcAddress. Returns 0 and prints why on
 * failure. destroy_context() then only forgets EGL's (none was made). */
typedef void *(*OsMesaCreateContextAttribs)(const int *, void *);
typedef unsigned char (*OsMesaMakeCurrent)(void *, void *, GLenum, GLsizei, GLsizei);
typedef void (*(*OsMesaGetProcAddress)(const char *))(void);
typedef void (*OsMesaDestroyContext)(void *);
static void *osmesa_context;
static OsMesaDestroyContext osmesa_destroy;

static inline int create_osmesa_context(void *buffer, int width, int height)
{
    void *lib = dlopen("libOSMesa.so.8", RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "no libOSMesa.so.8: %s\n", dlerror());
        return 0;
    }
    OsMesaCreateContextAttribs create = (OsMesaCreateContextAttribs)dlsym(lib, "OSMesaCreateContextAttribs");
    OsMesaMakeCurrent make_current = (OsMesaMakeCurrent)dlsym(lib, "OSMesaMakeCurrent");
    OsMesaGetProcAddress get_proc = (OsMesaGetProcAddress)dlsym(lib, "OSMesaGetProcAddress");
    osmesa_destroy = (OsMesaDestroyContext)dlsym(lib, "OSMesaDestroyContext");
    if (!create || !make_current || !get_proc || !osmesa_destroy) {
        fprintf(stderr, "libOSMesa.so.8 lacks an entry point\n");
        return 0;
    }
    /* OSMESA_FORMAT RGBA, depth 24, stencil 8, core profile 3.2 */
    const int attributes[] = {0x22, 0x1908, 0x30, 24, 0x31, 8, 0x33, 0x34, 0x36, 3, 0x37, 2, 0};
    osmesa_context = create(attributes, NULL);
    if (!osmesa_context || !make_current(osmesa_context, buffer, GL_UNSIGNED_BYTE, width, height)) {
        fprintf(stderr, "no OSMesa 3.2 core context\n");
        return 0;
    }
#define GL_LOAD_OSMESA(type, name)                                             \
    name = (type)get_proc(#name);                                              \
    if (!name) {                                                               \
        fprintf(stderr, "no GL entry point %s\n", #name);                      \
        return 0;                                                              \
    }
    GL_FUNCTIONS(GL_LOAD_OSMESA)
#undef GL_LOAD_OSMESA
    return 1;
}

static void destroy_context(void)
{
    if (osmesa_context) {
        osmesa_destroy(osmesa_context);
        osmesa_context = NULL;
        return;
    }
    eglMakeCurrent(egl_display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(egl_display, egl_context);
    eglTerminate(egl_display);
}

/* What the library's loader callback is: eglGetProcAddress with the
 * user-data argument the C API passes along (unused here). */
static inline const void *load_gl(const char *name, void *user_data)
{
    (void)user_data;
    return (const void *)eglGetProcAddress(name);
}

#endif
