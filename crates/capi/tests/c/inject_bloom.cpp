// A forward program with an HDR framebuffer of two colour textures and a
// depth renderbuffer, written as the LearnOpenGL "Bloom" chapter's: the
// cubes lit forward into the HDR framebuffer (the colour, and the bright
// parts into the second texture), a ping-pong Gaussian blur of the bright
// texture, and the composite of the colour and the blur into framebuffer
// 0. Its HDR framebuffer has the shape of a G-buffer (two colour textures
// and depth, drawn into, its textures read later), but no pass reads two
// of them together: `deferred-msaa inject` without a profile must leave it
// untouched, and say so.
//
// It draws FRAMES frames and writes the last one, read back before its
// swap, as raw RGBA8 into OUT_FILE. Shares the tutorial program's loader,
// shader class and cube (tutorial_program.hpp).
//
// Usage: inject_bloom OUT_FILE
#include "tutorial_program.hpp"

static const int WIDTH = 160;
static const int HEIGHT = 120;
static const int FRAMES = 3;

static const char *sceneFs = R"(
layout (location = 0) out vec4 FragColor;
layout (location = 1) out vec4 BrightColor;
in vec3 FragPos;
in vec3 Normal;
in vec2 TexCoords;
uniform vec3 diffuseColor;
void main()
{
    vec3 light = normalize(vec3(0.4, 1.0, 0.6));
    vec3 color = diffuseColor * (0.15 + 2.5 * max(dot(normalize(Normal), light), 0.0));
    FragColor = vec4(color, 1.0);
    float brightness = dot(color, vec3(0.2126, 0.7152, 0.0722));
    BrightColor = brightness > 1.0 ? vec4(color, 1.0) : vec4(0.0, 0.0, 0.0, 1.0);
}
)";

static const char *blurFs = R"(
out vec4 FragColor;
in vec2 TexCoords;
uniform sampler2D image;
uniform int horizontal;
const float weight[5] = float[] (0.227027, 0.1945946, 0.1216216, 0.054054, 0.016216);
void main()
{
    vec2 offset = 1.0 / vec2(textureSize(image, 0));
    vec3 result = texture(image, TexCoords).rgb * weight[0];
    vec2 step = horizontal == 1 ? vec2(offset.x, 0.0) : vec2(0.0, offset.y);
    for (int i = 1; i < 5; ++i) {
        result += texture(image, TexCoords + step * float(i)).rgb * weight[i];
        result += texture(image, TexCoords - step * float(i)).rgb * weight[i];
    }
    FragColor = vec4(result, 1.0);
}
)";

static const char *compositeFs = R"(
out vec4 FragColor;
in vec2 TexCoords;
uniform sampler2D scene;
uniform sampler2D bloomBlur;
void main()
{
    vec3 hdr = texture(scene, TexCoords).rgb + texture(bloomBlur, TexCoords).rgb;
    vec3 mapped = vec3(1.0) - exp(-hdr);
    FragColor = vec4(pow(mapped, vec3(1.0 / 2.2)), 1.0);
}
)";

int main(int argc, char **argv)
{
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s OUT_FILE\n", argv[0]);
        return 2;
    }
    glfwInit();
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 2);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GL_TRUE);
    glfwWindowHint(GLFW_RESIZABLE, GLFW_FALSE);
    GLFWwindow *window = glfwCreateWindow(WIDTH, HEIGHT, "Bloom", NULL, NULL);
    if (window == NULL) {
        std::fprintf(stderr, "Failed to create GLFW window\n");
        glfwTerminate();
        return 3;
    }
    glfwMakeContextCurrent(window);
    if (!loadGL())
        return 3;
    GLint major = 0, minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    if (major * 10 + minor < 33)
        glslVersion = "#version 150 core\n#extension GL_ARB_explicit_attrib_location : require\n";
    glEnable(GL_DEPTH_TEST);
    Shader scene(gBufferVs, sceneFs), blur(quadVs, blurFs), composite(quadVs, compositeFs);

    // The HDR framebuffer: two RGBA16F colour textures and depth.
    GLuint hdrFBO = 0, colorBuffers[2] = {0, 0}, rboDepth = 0;
    glGenFramebuffers(1, &hdrFBO);
    glBindFramebuffer(GL_FRAMEBUFFER, hdrFBO);
    for (unsigned i = 0; i < 2; i++) {
        colorBuffers[i] = makeTexture(WIDTH, HEIGHT, GL_RGBA16F, GL_FLOAT);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0 + i, GL_TEXTURE_2D, colorBuffers[i], 0);
    }
    glGenRenderbuffers(1, &rboDepth);
    glBindRenderbuffer(GL_RENDERBUFFER, rboDepth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT, WIDTH, HEIGHT);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rboDepth);
    unsigned int attachments[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glDrawBuffers(2, attachments);
    CHECK(glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE, "HDR framebuffer incomplete");
    // The ping-pong framebuffers of the blur: one colour texture each.
    GLuint pingpongFBO[2] = {0, 0}, pingpongColor[2] = {0, 0};
    glGenFramebuffers(2, pingpongFBO);
    for (int i = 0; i < 2; i++) {
        glBindFramebuffer(GL_FRAMEBUFFER, pingpongFBO[i]);
        pingpongColor[i] = makeTexture(WIDTH, HEIGHT, GL_RGBA16F, GL_FLOAT);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, pingpongColor[i], 0);
    }
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    blur.use();
    blur.setInt("image", 0);
    composite.use();
    composite.setInt("scene", 0);
    composite.setInt("bloomBlur", 1);

    Mat4 projection = perspective(45.0f * 3.14159265f / 180.0f, static_cast<float>(WIDTH) / HEIGHT, 0.1f, 100.0f);
    Mat4 view = lookAt(cameraPosition, cameraTarget, {0.0f, 1.0f, 0.0f});
    std::vector<unsigned char> pixels(static_cast<size_t>(WIDTH) * HEIGHT * 4);
    glViewport(0, 0, WIDTH, HEIGHT);
    glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
    for (int frame = 0; frame < FRAMES; frame++) {
        // 1. the scene into the HDR framebuffer
        glBindFramebuffer(GL_FRAMEBUFFER, hdrFBO);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        scene.use();
        scene.setMat4("projection", projection);
        scene.setMat4("view", view);
        for (int i = 0; i < 9; i++) {
            float fi = static_cast<float>(i);
            Vec3 position = {3.0f * static_cast<float>(i % 3 - 1), -0.5f, 3.0f * static_cast<float>(i / 3 - 1)};
            scene.setMat4("model", translate(position) * rotate(0.35f + 0.6f * fi, {1.0f, 0.8f, 0.3f}) * scale(0.6f));
            scene.setVec3("diffuseColor", {0.3f + 0.1f * fi, 0.9f - 0.05f * fi, 0.5f});
            renderCube();
        }
        // 2. the bright parts blurred, ten passes one texture at a time
        bool horizontal = true, first = true;
        blur.use();
        for (int i = 0; i < 10; i++) {
            glBindFramebuffer(GL_FRAMEBUFFER, pingpongFBO[horizontal]);
            blur.setInt("horizontal", horizontal);
            glActiveTexture(GL_TEXTURE0);
            glBindTexture(GL_TEXTURE_2D, first ? colorBuffers[1] : pingpongColor[!horizontal]);
            renderQuad();
            horizontal = !horizontal;
            first = false;
        }
        // 3. the composite into framebuffer 0
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        composite.use();
        glActiveTexture(GL_TEXTURE0);
        glBindTexture(GL_TEXTURE_2D, colorBuffers[0]);
        glActiveTexture(GL_TEXTURE1);
        glBindTexture(GL_TEXTURE_2D, pingpongColor[!horizontal]);
        renderQuad();
        checkGlErrors("a frame");
        if (frame == FRAMES - 1) {
            glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
            glReadBuffer(GL_BACK);
            glPixelStorei(GL_PACK_ALIGNMENT, 1);
            glReadPixels(0, 0, WIDTH, HEIGHT, GL_RGBA, GL_UNSIGNED_BYTE, pixels.data());
            glPixelStorei(GL_PACK_ALIGNMENT, 4);
        }
        glfwSwapBuffers(window);
        glfwPollEvents();
    }
    FILE *f = std::fopen(argv[1], "wb");
    CHECK(f != nullptr, "cannot write %s", argv[1]);
    if (f) {
        std::fwrite(pixels.data(), 1, pixels.size(), f);
        std::fclose(f);
    }
    glfwTerminate();
    if (failures) {
        std::fprintf(stderr, "%d check(s) failed\n", failures);
        return 1;
    }
    std::printf("ok\n");
    return 0;
}
