/* egl_gl.cuh — OpenGL through EGL for --draw's GL path, loaded at run time: libEGL.so.1 by dlopen,
 * every EGL extension and GL function through eglGetProcAddress, so the build needs no GL
 * header or library and a machine without them gets one line saying what is missing. Host
 * C++ only (no CUDA): the binary (cuda/draw/draw.cu) and the host check
 * (cuda/hostcheck/draw_hostcheck.cu, on Mesa's llvmpipe) use it alike.
 *
 * GlDraw::open makes a core 3.3 context with no surface on the EGL device whose CUDA device
 * is `cuda_device` (EGL_NV_device_cuda; any device, then the default display, where none
 * says), a W×H framebuffer (RGBA8, depth 24), a vertex buffer of N·P points × 6 floats
 * (position, unit tangent; docs/interfaces.md "Drawing on the GPU"), line strips one a
 * strand (primitive restart), and the head sphere. draw() clears, draws the head and the
 * strands and times the draw with GL_TIME_ELAPSED; the view and shading are view.cuh's. */
#ifndef HB_EGL_GL_H
#define HB_EGL_GL_H

#include <dlfcn.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <utility>
#include <vector>

#include "draw/view.cuh"

namespace hb_gl {

typedef void *EGLDisplay, *EGLConfig, *EGLContext, *EGLSurface, *EGLDeviceEXT;
typedef int32_t EGLint;
typedef unsigned EGLBoolean, EGLenum;
typedef void (*Proc)(void);
typedef unsigned GLenum, GLuint, GLbitfield;
typedef int GLint, GLsizei;
typedef intptr_t GLsizeiptr, GLintptr;
typedef float GLfloat;
typedef unsigned char GLboolean;
typedef uint64_t GLuint64;

enum : EGLint {
    EGL_NONE = 0x3038,
    EGL_SURFACE_TYPE = 0x3033,
    EGL_PBUFFER_BIT = 0x0001,
    EGL_RENDERABLE_TYPE = 0x3040,
    EGL_OPENGL_BIT = 0x0008,
    EGL_OPENGL_API = 0x30A2,
    EGL_CONTEXT_MAJOR_VERSION = 0x3098,
    EGL_CONTEXT_MINOR_VERSION = 0x30FB,
    EGL_CONTEXT_OPENGL_PROFILE_MASK = 0x30FD,
    EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT = 0x0001,
    EGL_PLATFORM_DEVICE_EXT = 0x313F,
    EGL_CUDA_DEVICE_NV = 0x323A,
};
enum : GLenum {
    GL_ARRAY_BUFFER = 0x8892,
    GL_ELEMENT_ARRAY_BUFFER = 0x8893,
    GL_STATIC_DRAW = 0x88E4,
    GL_DYNAMIC_DRAW = 0x88E8,
    GL_FLOAT = 0x1406,
    GL_UNSIGNED_INT = 0x1405,
    GL_UNSIGNED_BYTE = 0x1401,
    GL_LINE_STRIP = 0x0003,
    GL_TRIANGLES = 0x0004,
    GL_VERTEX_SHADER = 0x8B31,
    GL_FRAGMENT_SHADER = 0x8B30,
    GL_COMPILE_STATUS = 0x8B81,
    GL_LINK_STATUS = 0x8B82,
    GL_FRAMEBUFFER = 0x8D40,
    GL_RENDERBUFFER = 0x8D41,
    GL_RGBA8 = 0x8058,
    GL_RGBA = 0x1908,
    GL_DEPTH_COMPONENT24 = 0x81A6,
    GL_COLOR_ATTACHMENT0 = 0x8CE0,
    GL_DEPTH_ATTACHMENT = 0x8D00,
    GL_FRAMEBUFFER_COMPLETE = 0x8CD5,
    GL_DEPTH_TEST = 0x0B71,
    GL_PRIMITIVE_RESTART = 0x8F9D,
    GL_COLOR_BUFFER_BIT = 0x4000,
    GL_DEPTH_BUFFER_BIT = 0x0100,
    GL_TIME_ELAPSED = 0x88BF,
    GL_QUERY_RESULT = 0x8866,
    GL_RENDERER = 0x1F01,
    GL_VERSION = 0x1F02,
    GL_LESS = 0x0201,
};
constexpr GLuint kRestart = 0xffffffffu;

/* the EGL and GL entry points used, each looked up once */
#define HB_EGL_FUNCS(X)                                                                                                \
    X(EGLBoolean, eglInitialize, (EGLDisplay, EGLint *, EGLint *))                                                     \
    X(EGLBoolean, eglBindAPI, (EGLenum))                                                                               \
    X(EGLBoolean, eglChooseConfig, (EGLDisplay, const EGLint *, EGLConfig *, EGLint, EGLint *))                        \
    X(EGLContext, eglCreateContext, (EGLDisplay, EGLConfig, EGLContext, const EGLint *))                               \
    X(EGLBoolean, eglMakeCurrent, (EGLDisplay, EGLSurface, EGLSurface, EGLContext))                                    \
    X(EGLBoolean, eglDestroyContext, (EGLDisplay, EGLContext))                                                         \
    X(EGLBoolean, eglTerminate, (EGLDisplay))                                                                          \
    X(EGLint, eglGetError, (void))                                                                                     \
    X(EGLDisplay, eglGetDisplay, (void *))                                                                             \
    X(EGLBoolean, eglQueryDevicesEXT, (EGLint, EGLDeviceEXT *, EGLint *))                                              \
    X(EGLBoolean, eglQueryDeviceAttribEXT, (EGLDeviceEXT, EGLint, intptr_t *))                                         \
    X(EGLDisplay, eglGetPlatformDisplayEXT, (EGLenum, void *, const EGLint *))
#define HB_GL_FUNCS(X)                                                                                                 \
    X(void, glGenBuffers, (GLsizei, GLuint *))                                                                         \
    X(void, glBindBuffer, (GLenum, GLuint))                                                                            \
    X(void, glBufferData, (GLenum, GLsizeiptr, const void *, GLenum))                                                  \
    X(void, glBufferSubData, (GLenum, GLintptr, GLsizeiptr, const void *))                                             \
    X(void, glDeleteBuffers, (GLsizei, const GLuint *))                                                                \
    X(void, glGenVertexArrays, (GLsizei, GLuint *))                                                                    \
    X(void, glBindVertexArray, (GLuint))                                                                               \
    X(void, glDeleteVertexArrays, (GLsizei, const GLuint *))                                                           \
    X(void, glVertexAttribPointer, (GLuint, GLint, GLenum, GLboolean, GLsizei, const void *))                          \
    X(void, glEnableVertexAttribArray, (GLuint))                                                                       \
    X(GLuint, glCreateShader, (GLenum))                                                                                \
    X(void, glShaderSource, (GLuint, GLsizei, const char *const *, const GLint *))                                     \
    X(void, glCompileShader, (GLuint))                                                                                 \
    X(void, glGetShaderiv, (GLuint, GLenum, GLint *))                                                                  \
    X(void, glGetShaderInfoLog, (GLuint, GLsizei, GLsizei *, char *))                                                  \
    X(GLuint, glCreateProgram, (void))                                                                                 \
    X(void, glAttachShader, (GLuint, GLuint))                                                                          \
    X(void, glLinkProgram, (GLuint))                                                                                   \
    X(void, glGetProgramiv, (GLuint, GLenum, GLint *))                                                                 \
    X(void, glGetProgramInfoLog, (GLuint, GLsizei, GLsizei *, char *))                                                 \
    X(void, glUseProgram, (GLuint))                                                                                    \
    X(void, glDeleteProgram, (GLuint))                                                                                 \
    X(void, glDeleteShader, (GLuint))                                                                                  \
    X(GLint, glGetUniformLocation, (GLuint, const char *))                                                             \
    X(void, glUniform4f, (GLint, GLfloat, GLfloat, GLfloat, GLfloat))                                                  \
    X(void, glUniform3f, (GLint, GLfloat, GLfloat, GLfloat))                                                           \
    X(void, glUniform1f, (GLint, GLfloat))                                                                             \
    X(void, glGenFramebuffers, (GLsizei, GLuint *))                                                                    \
    X(void, glBindFramebuffer, (GLenum, GLuint))                                                                       \
    X(void, glDeleteFramebuffers, (GLsizei, const GLuint *))                                                           \
    X(void, glGenRenderbuffers, (GLsizei, GLuint *))                                                                   \
    X(void, glBindRenderbuffer, (GLenum, GLuint))                                                                      \
    X(void, glRenderbufferStorage, (GLenum, GLenum, GLsizei, GLsizei))                                                 \
    X(void, glDeleteRenderbuffers, (GLsizei, const GLuint *))                                                          \
    X(void, glFramebufferRenderbuffer, (GLenum, GLenum, GLenum, GLuint))                                               \
    X(GLenum, glCheckFramebufferStatus, (GLenum))                                                                      \
    X(void, glViewport, (GLint, GLint, GLsizei, GLsizei))                                                              \
    X(void, glClearColor, (GLfloat, GLfloat, GLfloat, GLfloat))                                                        \
    X(void, glClearDepthf, (GLfloat))                                                                                  \
    X(void, glClear, (GLbitfield))                                                                                     \
    X(void, glEnable, (GLenum))                                                                                        \
    X(void, glDepthFunc, (GLenum))                                                                                     \
    X(void, glPrimitiveRestartIndex, (GLuint))                                                                         \
    X(void, glDrawElements, (GLenum, GLsizei, GLenum, const void *))                                                   \
    X(void, glGenQueries, (GLsizei, GLuint *))                                                                         \
    X(void, glDeleteQueries, (GLsizei, const GLuint *))                                                                \
    X(void, glBeginQuery, (GLenum, GLuint))                                                                            \
    X(void, glEndQuery, (GLenum))                                                                                      \
    X(void, glGetQueryObjectui64v, (GLuint, GLenum, GLuint64 *))                                                       \
    X(void, glReadPixels, (GLint, GLint, GLsizei, GLsizei, GLenum, GLenum, void *))                                    \
    X(void, glFinish, (void))                                                                                          \
    X(GLenum, glGetError, (void))                                                                                      \
    X(const unsigned char *, glGetString, (GLenum))

#define HB_DECLARE(ret, name, args) ret(*name) args = nullptr;

struct Api {
    void *lib = nullptr;
    Proc (*eglGetProcAddress)(const char *) = nullptr;
    HB_EGL_FUNCS(HB_DECLARE)
    HB_GL_FUNCS(HB_DECLARE)
};
#undef HB_DECLARE

/* hair: the view's orthographic mapping and Kajiya–Kay (view.cuh's constants) */
static const char *kHairVertex = R"(#version 330 core
layout(location = 0) in vec3 pos;
layout(location = 1) in vec3 tan;
uniform vec4 view; // hw, hh, E, P
out vec3 v_tan;
out float v_s;
void main() {
    gl_Position = vec4(pos.x / view.x, pos.y / view.y, -pos.z / view.z, 1.0);
    v_tan = tan;
    v_s = float(gl_VertexID % int(view.w)) / (view.w - 1.0);
})";
static const char *kHairFragment = R"(#version 330 core
uniform vec3 light;
uniform vec3 half_vec;
uniform vec3 root;
uniform vec3 tip;
uniform vec4 k; // ambient, diffuse, specular, shininess
in vec3 v_tan;
in float v_s;
out vec4 color;
void main() {
    vec3 T = normalize(v_tan);
    float tl = dot(T, light), th = dot(T, half_vec);
    float diffuse = sqrt(max(1.0 - tl * tl, 0.0));
    float specular = pow(sqrt(max(1.0 - th * th, 0.0)), k.w);
    color = vec4(mix(root, tip, v_s) * (k.x + k.y * diffuse) + k.z * specular, 1.0);
})";
static const char *kHeadVertex = R"(#version 330 core
layout(location = 0) in vec3 pos;
uniform vec4 view;
out vec3 v_n;
void main() {
    gl_Position = vec4(pos.x / view.x, pos.y / view.y, -pos.z / view.z, 1.0);
    v_n = pos;
})";
static const char *kHeadFragment = R"(#version 330 core
uniform vec3 light;
uniform vec3 skin;
uniform float ambient;
in vec3 v_n;
out vec4 color;
void main() {
    float lambert = max(dot(normalize(v_n), light), 0.0);
    color = vec4(skin * (ambient + (1.0 - ambient) * lambert), 1.0);
})";

class GlDraw {
  public:
    Api gl;
    EGLDisplay dpy = nullptr;
    EGLContext ctx = nullptr;
    GLuint fbo = 0, color = 0, depth = 0, vbo = 0, ibo = 0, vao = 0, head_vbo = 0, head_ibo = 0, head_vao = 0;
    GLuint hair_prog = 0, head_prog = 0;
    std::vector<GLuint> queries;
    GLsizei n_index = 0, n_head = 0;
    hb_draw::View v{};
    char renderer[160] = "";

    /* false with one line in `why` where EGL, a context or GL is missing */
    bool open(const hb_draw::View &view, int64_t N, int64_t P, int cuda_device, int n_queries, char *why, size_t wl)
    {
        v = view;
        gl.lib = dlopen("libEGL.so.1", RTLD_NOW | RTLD_LOCAL);
        if (!gl.lib) return say(why, wl, "libEGL.so.1 cannot be loaded (%s)", dlerror());
        gl.eglGetProcAddress = (Proc(*)(const char *))dlsym(gl.lib, "eglGetProcAddress");
        if (!gl.eglGetProcAddress) return say(why, wl, "libEGL.so.1 has no eglGetProcAddress");
#define HB_LOAD(ret, name, args)                                                                                       \
    gl.name = (ret(*) args)dlsym(gl.lib, #name);                                                                       \
    if (!gl.name) gl.name = (ret(*) args)gl.eglGetProcAddress(#name);
        HB_EGL_FUNCS(HB_LOAD)
#undef HB_LOAD
        if (!gl.eglInitialize || !gl.eglChooseConfig || !gl.eglCreateContext || !gl.eglMakeCurrent)
            return say(why, wl, "libEGL.so.1 lacks the EGL 1.4 entry points");
        if (!display(cuda_device, why, wl)) return false;
        if (!context(why, wl)) return false;
#define HB_LOAD(ret, name, args)                                                                                       \
    gl.name = (ret(*) args)gl.eglGetProcAddress(#name);                                                                \
    if (!gl.name) return say(why, wl, "the GL driver has no %s", #name);
        HB_GL_FUNCS(HB_LOAD)
#undef HB_LOAD
        snprintf(renderer, sizeof renderer, "%s, %s", (const char *)gl.glGetString(GL_RENDERER),
                 (const char *)gl.glGetString(GL_VERSION));
        return buffers(N, P, n_queries, why, wl) && programs(why, wl);
    }

    /* clear, head, strands, the GL time of the draw into query `q` (no wait) */
    void draw(int q)
    {
        gl.glBeginQuery(GL_TIME_ELAPSED, queries[(size_t)q]);
        gl.glBindFramebuffer(GL_FRAMEBUFFER, fbo);
        gl.glViewport(0, 0, v.W, v.H);
        const uint32_t bg = hb_draw::kBackground;
        gl.glClearColor((bg & 0xff) / 255.0f, ((bg >> 8) & 0xff) / 255.0f, ((bg >> 16) & 0xff) / 255.0f, 1.0f);
        gl.glClearDepthf(1.0f);
        gl.glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        gl.glUseProgram(head_prog);
        gl.glBindVertexArray(head_vao);
        gl.glDrawElements(GL_TRIANGLES, n_head, GL_UNSIGNED_INT, nullptr);
        gl.glUseProgram(hair_prog);
        gl.glBindVertexArray(vao);
        gl.glDrawElements(GL_LINE_STRIP, n_index, GL_UNSIGNED_INT, nullptr);
        gl.glEndQuery(GL_TIME_ELAPSED);
    }

    /* nanoseconds of query q (waits for it) */
    double elapsed_ms(int q)
    {
        GLuint64 ns = 0;
        gl.glGetQueryObjectui64v(queries[(size_t)q], GL_QUERY_RESULT, &ns);
        return (double)ns * 1e-6;
    }

    /* the framebuffer as RGBA8, row 0 at the top */
    void read(std::vector<uint32_t> &rgba)
    {
        rgba.assign((size_t)v.W * v.H, 0);
        gl.glBindFramebuffer(GL_FRAMEBUFFER, fbo);
        gl.glReadPixels(0, 0, v.W, v.H, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
        for (int r = 0; r < v.H / 2; r++)
            for (int c = 0; c < v.W; c++) std::swap(rgba[(size_t)r * v.W + c], rgba[(size_t)(v.H - 1 - r) * v.W + c]);
    }

    void close()
    {
        if (gl.glDeleteBuffers && ctx) {
            const GLuint bufs[] = {vbo, ibo, head_vbo, head_ibo};
            gl.glDeleteBuffers(4, bufs);
            const GLuint vaos[] = {vao, head_vao};
            gl.glDeleteVertexArrays(2, vaos);
            gl.glDeleteRenderbuffers(1, &color);
            gl.glDeleteRenderbuffers(1, &depth);
            gl.glDeleteFramebuffers(1, &fbo);
            gl.glDeleteProgram(hair_prog);
            gl.glDeleteProgram(head_prog);
            if (!queries.empty()) gl.glDeleteQueries((GLsizei)queries.size(), queries.data());
        }
        if (ctx) gl.eglMakeCurrent(dpy, nullptr, nullptr, nullptr), gl.eglDestroyContext(dpy, ctx);
        if (dpy) gl.eglTerminate(dpy);
        ctx = dpy = nullptr;
        if (gl.lib) dlclose(gl.lib);
        gl.lib = nullptr;
    }

  private:
    static bool say(char *why, size_t wl, const char *fmt, ...) __attribute__((format(printf, 3, 4)))
    {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(why, wl, fmt, ap);
        va_end(ap);
        return false;
    }

    bool display(int cuda_device, char *why, size_t wl)
    {
        EGLDeviceEXT devs[16];
        EGLint n = 0;
        if (gl.eglQueryDevicesEXT && gl.eglGetPlatformDisplayEXT && gl.eglQueryDevicesEXT(16, devs, &n) && n > 0) {
            int pick = 0;
            for (int i = 0; i < n && gl.eglQueryDeviceAttribEXT; i++) {
                intptr_t id = -1;
                if (gl.eglQueryDeviceAttribEXT(devs[i], EGL_CUDA_DEVICE_NV, &id) && id == cuda_device) {
                    pick = i;
                    break;
                }
            }
            dpy = gl.eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devs[pick], nullptr);
        }
        if (!dpy && gl.eglGetDisplay) dpy = gl.eglGetDisplay(nullptr);
        EGLint major = 0, minor = 0;
        if (!dpy || !gl.eglInitialize(dpy, &major, &minor))
            return say(why, wl, "EGL has no display to draw on (eglInitialize: 0x%x)", gl.eglGetError());
        return true;
    }

    bool context(char *why, size_t wl)
    {
        const EGLint cfg_attrs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
        EGLConfig cfg = nullptr;
        EGLint n = 0;
        if (!gl.eglBindAPI(EGL_OPENGL_API)) return say(why, wl, "EGL does not offer desktop OpenGL");
        if (!gl.eglChooseConfig(dpy, cfg_attrs, &cfg, 1, &n) || n < 1)
            return say(why, wl, "EGL has no OpenGL configuration (0x%x)", gl.eglGetError());
        const EGLint ctx_attrs[] = {
            EGL_CONTEXT_MAJOR_VERSION,           3,       EGL_CONTEXT_MINOR_VERSION, 3, EGL_CONTEXT_OPENGL_PROFILE_MASK,
            EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
        ctx = gl.eglCreateContext(dpy, cfg, nullptr, ctx_attrs);
        if (!ctx) return say(why, wl, "EGL gives no OpenGL 3.3 core context (0x%x)", gl.eglGetError());
        if (!gl.eglMakeCurrent(dpy, nullptr, nullptr, ctx))
            return say(why, wl, "EGL cannot make a context current without a surface (0x%x)", gl.eglGetError());
        return true;
    }

    bool buffers(int64_t N, int64_t P, int n_queries, char *why, size_t wl)
    {
        gl.glGenFramebuffers(1, &fbo);
        gl.glBindFramebuffer(GL_FRAMEBUFFER, fbo);
        gl.glGenRenderbuffers(1, &color);
        gl.glBindRenderbuffer(GL_RENDERBUFFER, color);
        gl.glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, v.W, v.H);
        gl.glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color);
        gl.glGenRenderbuffers(1, &depth);
        gl.glBindRenderbuffer(GL_RENDERBUFFER, depth);
        gl.glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, v.W, v.H);
        gl.glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth);
        if (gl.glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
            return say(why, wl, "GL cannot make a %dx%d framebuffer", v.W, v.H);
        gl.glEnable(GL_DEPTH_TEST);
        gl.glDepthFunc(GL_LESS);
        gl.glEnable(GL_PRIMITIVE_RESTART);
        gl.glPrimitiveRestartIndex(kRestart);
        /* strands: positions and tangents, written each frame (by CUDA in the binary) */
        gl.glGenVertexArrays(1, &vao);
        gl.glBindVertexArray(vao);
        gl.glGenBuffers(1, &vbo);
        gl.glBindBuffer(GL_ARRAY_BUFFER, vbo);
        gl.glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(N * P * 6 * sizeof(float)), nullptr, GL_DYNAMIC_DRAW);
        gl.glVertexAttribPointer(0, 3, GL_FLOAT, 0, 6 * sizeof(float), nullptr);
        gl.glVertexAttribPointer(1, 3, GL_FLOAT, 0, 6 * sizeof(float), (const void *)(3 * sizeof(float)));
        gl.glEnableVertexAttribArray(0);
        gl.glEnableVertexAttribArray(1);
        std::vector<GLuint> idx;
        idx.reserve((size_t)(N * (P + 1)));
        for (int64_t i = 0; i < N; i++) {
            for (int64_t k = 0; k < P; k++) idx.push_back((GLuint)(i * P + k));
            idx.push_back(kRestart);
        }
        n_index = (GLsizei)idx.size();
        gl.glGenBuffers(1, &ibo);
        gl.glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo);
        gl.glBufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)(idx.size() * sizeof(GLuint)), idx.data(), GL_STATIC_DRAW);
        head();
        queries.resize((size_t)n_queries);
        gl.glGenQueries(n_queries, queries.data());
        if (gl.glGetError() != 0) return say(why, wl, "GL failed making the buffers (%lld points)", (long long)(N * P));
        return true;
    }

    void head()
    {
        const int rings = 48, sectors = 96;
        std::vector<float> p;
        for (int r = 0; r <= rings; r++)
            for (int s = 0; s <= sectors; s++) {
                const double phi = M_PI * r / rings, th = 2 * M_PI * s / sectors;
                p.push_back((float)(v.R * sin(phi) * sin(th)));
                p.push_back((float)(v.R * cos(phi)));
                p.push_back((float)(v.R * sin(phi) * cos(th)));
            }
        std::vector<GLuint> t;
        for (int r = 0; r < rings; r++)
            for (int s = 0; s < sectors; s++) {
                const GLuint a = (GLuint)(r * (sectors + 1) + s), b = a + sectors + 1;
                t.insert(t.end(), {a, b, a + 1, a + 1, b, b + 1});
            }
        n_head = (GLsizei)t.size();
        gl.glGenVertexArrays(1, &head_vao);
        gl.glBindVertexArray(head_vao);
        gl.glGenBuffers(1, &head_vbo);
        gl.glBindBuffer(GL_ARRAY_BUFFER, head_vbo);
        gl.glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(p.size() * sizeof(float)), p.data(), GL_STATIC_DRAW);
        gl.glVertexAttribPointer(0, 3, GL_FLOAT, 0, 3 * sizeof(float), nullptr);
        gl.glEnableVertexAttribArray(0);
        gl.glGenBuffers(1, &head_ibo);
        gl.glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, head_ibo);
        gl.glBufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)(t.size() * sizeof(GLuint)), t.data(), GL_STATIC_DRAW);
    }

    GLuint program(const char *vs, const char *fs, char *why, size_t wl)
    {
        GLuint sh[2], prog = gl.glCreateProgram();
        const char *src[2] = {vs, fs};
        const GLenum kind[2] = {GL_VERTEX_SHADER, GL_FRAGMENT_SHADER};
        GLint ok = 0;
        for (int i = 0; i < 2; i++) {
            sh[i] = gl.glCreateShader(kind[i]);
            gl.glShaderSource(sh[i], 1, &src[i], nullptr);
            gl.glCompileShader(sh[i]);
            gl.glGetShaderiv(sh[i], GL_COMPILE_STATUS, &ok);
            if (!ok) {
                char log[200] = "";
                gl.glGetShaderInfoLog(sh[i], sizeof log, nullptr, log);
                for (char *c = log; *c; c++)
                    if (*c == '\n') *c = ' ';
                say(why, wl, "GL cannot compile the %s shader: %s", i ? "fragment" : "vertex", log);
                return 0;
            }
            gl.glAttachShader(prog, sh[i]);
        }
        gl.glLinkProgram(prog);
        gl.glGetProgramiv(prog, GL_LINK_STATUS, &ok);
        gl.glDeleteShader(sh[0]);
        gl.glDeleteShader(sh[1]);
        if (!ok) say(why, wl, "GL cannot link the shaders");
        return ok ? prog : 0;
    }

    bool programs(char *why, size_t wl)
    {
        namespace d = hb_draw;
        hair_prog = program(kHairVertex, kHairFragment, why, wl);
        head_prog = program(kHeadVertex, kHeadFragment, why, wl);
        if (!hair_prog || !head_prog) return false;
        gl.glUseProgram(hair_prog);
        gl.glUniform4f(gl.glGetUniformLocation(hair_prog, "view"), v.hw, v.hh, v.E, (float)v.P);
        gl.glUniform3f(gl.glGetUniformLocation(hair_prog, "light"), v.light[0], v.light[1], v.light[2]);
        gl.glUniform3f(gl.glGetUniformLocation(hair_prog, "half_vec"), v.half[0], v.half[1], v.half[2]);
        gl.glUniform3f(gl.glGetUniformLocation(hair_prog, "root"), v.root[0], v.root[1], v.root[2]);
        gl.glUniform3f(gl.glGetUniformLocation(hair_prog, "tip"), v.tip[0], v.tip[1], v.tip[2]);
        gl.glUniform4f(gl.glGetUniformLocation(hair_prog, "k"), d::kAmbient, d::kDiffuse, d::kSpecular, d::kShininess);
        gl.glUseProgram(head_prog);
        gl.glUniform4f(gl.glGetUniformLocation(head_prog, "view"), v.hw, v.hh, v.E, (float)v.P);
        gl.glUniform3f(gl.glGetUniformLocation(head_prog, "light"), v.light[0], v.light[1], v.light[2]);
        gl.glUniform3f(gl.glGetUniformLocation(head_prog, "skin"), v.skin[0], v.skin[1], v.skin[2]);
        gl.glUniform1f(gl.glGetUniformLocation(head_prog, "ambient"), d::kAmbient);
        return gl.glGetError() == 0 || say(why, wl, "GL failed setting the shaders' uniforms");
    }
};

} // namespace hb_gl

#endif
