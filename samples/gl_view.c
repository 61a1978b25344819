/* An OpenGL host (a GLFW window with an OpenGL context, as the Open CASCADE viewer, VTK or Qt's
 * OpenGL widgets are) showing cadr's frames without copying them through the CPU: cadr copies
 * each frame on the GPU into memory it exports as a file descriptor
 * (cadr_renderer_create_for_export); the host imports that memory once as an OpenGL buffer
 * (GL_EXT_memory_object_fd), uploads the frame from it into a texture on the GPU, and blits the
 * texture into its window. Where the drivers cannot share memory, it reads each frame back
 * (cadr_renderer_read_pixels) and says so.
 *
 *   gl_view [scene] [--frames N] [--read-back] [--self-test DIR]
 *
 * It orbits the scene for N frames (default 60) and prints which path it took, the bytes read
 * back through the CPU per frame and the frames per second. --read-back takes the read-back path
 * on purpose. --self-test DIR also writes the offscreen render of the last frame's camera
 * (DIR/offscreen.png), prints "screenshot ready WxH" and keeps showing that frame until a line
 * arrives on stdin, so that a test can grab the window and compare. */
#define _POSIX_C_SOURCE 199309L
#define GLFW_INCLUDE_GLEXT
#include <GLFW/glfw3.h>

#include "common/sample.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { WIDTH = 320, HEIGHT = 240 };

/* The OpenGL functions beyond 1.1, loaded through GLFW. */
struct Gl {
  PFNGLGENBUFFERSPROC GenBuffers;
  PFNGLBINDBUFFERPROC BindBuffer;
  PFNGLDELETEBUFFERSPROC DeleteBuffers;
  PFNGLGENFRAMEBUFFERSPROC GenFramebuffers;
  PFNGLBINDFRAMEBUFFERPROC BindFramebuffer;
  PFNGLFRAMEBUFFERTEXTURE2DPROC FramebufferTexture2D;
  PFNGLBLITFRAMEBUFFERPROC BlitFramebuffer;
  PFNGLDELETEFRAMEBUFFERSPROC DeleteFramebuffers;
  PFNGLTEXSTORAGE2DPROC TexStorage2D;
  /* GL_EXT_memory_object(_fd); NULL where the driver lacks them. */
  PFNGLCREATEMEMORYOBJECTSEXTPROC CreateMemoryObjectsEXT;
  PFNGLDELETEMEMORYOBJECTSEXTPROC DeleteMemoryObjectsEXT;
  PFNGLIMPORTMEMORYFDEXTPROC ImportMemoryFdEXT;
  PFNGLBUFFERSTORAGEMEMEXTPROC BufferStorageMemEXT;
};

#define LOAD(gl, name, type) ((gl)->name = (type)glfwGetProcAddress("gl" #name))

static int load_gl(struct Gl *gl) {
  LOAD(gl, GenBuffers, PFNGLGENBUFFERSPROC);
  LOAD(gl, BindBuffer, PFNGLBINDBUFFERPROC);
  LOAD(gl, DeleteBuffers, PFNGLDELETEBUFFERSPROC);
  LOAD(gl, GenFramebuffers, PFNGLGENFRAMEBUFFERSPROC);
  LOAD(gl, BindFramebuffer, PFNGLBINDFRAMEBUFFERPROC);
  LOAD(gl, FramebufferTexture2D, PFNGLFRAMEBUFFERTEXTURE2DPROC);
  LOAD(gl, BlitFramebuffer, PFNGLBLITFRAMEBUFFERPROC);
  LOAD(gl, DeleteFramebuffers, PFNGLDELETEFRAMEBUFFERSPROC);
  LOAD(gl, TexStorage2D, PFNGLTEXSTORAGE2DPROC);
  if (glfwExtensionSupported("GL_EXT_memory_object") &&
      glfwExtensionSupported("GL_EXT_memory_object_fd")) {
    LOAD(gl, CreateMemoryObjectsEXT, PFNGLCREATEMEMORYOBJECTSEXTPROC);
    LOAD(gl, DeleteMemoryObjectsEXT, PFNGLDELETEMEMORYOBJECTSEXTPROC);
    LOAD(gl, ImportMemoryFdEXT, PFNGLIMPORTMEMORYFDEXTPROC);
    LOAD(gl, BufferStorageMemEXT, PFNGLBUFFERSTORAGEMEMEXTPROC);
  }
  return gl->GenBuffers && gl->BindBuffer && gl->GenFramebuffers && gl->BlitFramebuffer &&
         gl->FramebufferTexture2D && gl->TexStorage2D;
}

/* What the window shows: a texture the frames are uploaded into, and where they come from. */
struct Host {
  struct Gl gl;
  GLuint texture, framebuffer;
  /* The shared path: cadr's exported memory as a buffer; 0 on the read-back path. */
  GLuint memory_object, pixel_buffer;
  uint64_t generation;
  /* The read-back path: the frame in host memory. */
  uint8_t *pixels;
};

/* Imports the renderer's exported memory as a pixel buffer; 0 when the driver refuses it. */
static int import_frames(struct Host *host, CadrRenderer renderer) {
  CadrExportedFrame frame;
  memset(&frame, 0, sizeof frame);
  frame.size = sizeof frame;
  CADR_CHECK(cadr_renderer_exported_frame(renderer, &frame));
  if (host->memory_object != 0) {
    host->gl.DeleteBuffers(1, &host->pixel_buffer);
    host->gl.DeleteMemoryObjectsEXT(1, &host->memory_object);
  }
  while (glGetError() != GL_NO_ERROR) {
    /* Earlier errors are not the import's. */
  }
  host->gl.CreateMemoryObjectsEXT(1, &host->memory_object);
  /* The import takes the file descriptor. */
  host->gl.ImportMemoryFdEXT(host->memory_object, frame.allocation_size,
                             GL_HANDLE_TYPE_OPAQUE_FD_EXT, frame.fd);
  host->gl.GenBuffers(1, &host->pixel_buffer);
  host->gl.BindBuffer(GL_PIXEL_UNPACK_BUFFER, host->pixel_buffer);
  host->gl.BufferStorageMemEXT(GL_PIXEL_UNPACK_BUFFER, (GLsizeiptr)frame.row_bytes * frame.height,
                               host->memory_object, 0);
  host->gl.BindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
  host->generation = frame.generation;
  if (glGetError() != GL_NO_ERROR) {
    host->gl.DeleteBuffers(1, &host->pixel_buffer);
    host->gl.DeleteMemoryObjectsEXT(1, &host->memory_object);
    host->memory_object = 0;
    host->pixel_buffer = 0;
    return 0;
  }
  return 1;
}

/* Puts the renderer's last frame on the window: from the shared buffer on the GPU, or from the
 * bytes read back. Returns the bytes read back through the CPU. */
static size_t show_frame(struct Host *host, CadrRenderer renderer) {
  size_t read_back = 0;
  glBindTexture(GL_TEXTURE_2D, host->texture);
  if (host->pixel_buffer != 0) {
    host->gl.BindBuffer(GL_PIXEL_UNPACK_BUFFER, host->pixel_buffer);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, WIDTH, HEIGHT, GL_RGBA, GL_UNSIGNED_BYTE, NULL);
    host->gl.BindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
  } else {
    read_back = (size_t)WIDTH * HEIGHT * 4;
    CADR_CHECK(cadr_renderer_read_pixels(renderer, host->pixels, read_back));
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, WIDTH, HEIGHT, GL_RGBA, GL_UNSIGNED_BYTE,
                    host->pixels);
  }
  /* Row 0 of a frame is its top row: blit it to the window's top (GL counts rows upwards). */
  host->gl.BindFramebuffer(GL_READ_FRAMEBUFFER, host->framebuffer);
  host->gl.BindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  host->gl.BlitFramebuffer(0, 0, WIDTH, HEIGHT, 0, HEIGHT, WIDTH, 0, GL_COLOR_BUFFER_BIT,
                           GL_NEAREST);
  host->gl.BindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  return read_back;
}

static double now_seconds(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + (double)t.tv_nsec / 1e9;
}

/* The scene's bounds seen from a direction turned `angle` about the up axis. */
static void orbit_camera(const struct CadrBounds *bounds, double angle, struct CadrCamera *camera) {
  const double direction[3] = {cos(angle), 0.6, sin(angle)};
  CADR_CHECK(cadr_camera_fit(bounds, (double)WIDTH / HEIGHT, direction, camera));
}

int main(int argc, char **argv) {
  const char *source = "gen:demo", *test_dir = NULL;
  int frames = 60, read_back_only = 0, frame, i;
  struct Host host;
  struct CadrContextOptions options;
  struct CadrLoadResult loaded;
  struct CadrBounds bounds;
  struct CadrCamera camera;
  struct CadrFrameStats stats;
  CadrContext context;
  CadrScene scene;
  CadrRenderer renderer = NULL;
  CadrNode root;
  GLFWwindow *window;
  size_t read_back = 0;
  double start;
  uint64_t validation_errors = 0;

  for (i = 1; i < argc; ++i) {
    if (strcmp(argv[i], "--frames") == 0 && i + 1 < argc) {
      frames = atoi(argv[++i]);
    } else if (strcmp(argv[i], "--read-back") == 0) {
      read_back_only = 1;
    } else if (strcmp(argv[i], "--self-test") == 0 && i + 1 < argc) {
      test_dir = argv[++i];
    } else {
      source = argv[i];
    }
  }
  memset(&host, 0, sizeof host);
  if (!glfwInit()) {
    fprintf(stderr, "gl_view: GLFW could not start (no display?)\n");
    return 1;
  }
  glfwWindowHint(GLFW_CLIENT_API, GLFW_OPENGL_API);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 0);
  glfwWindowHint(GLFW_RESIZABLE, GLFW_FALSE);
  window = glfwCreateWindow(WIDTH, HEIGHT, "cadr in OpenGL", NULL, NULL);
  if (window == NULL) {
    fprintf(stderr, "gl_view: no OpenGL 3.0 window\n");
    return 1;
  }
  glfwMakeContextCurrent(window);
  if (!load_gl(&host.gl)) {
    fprintf(stderr, "gl_view: the OpenGL driver lacks framebuffer blits or texture storage\n");
    return 1;
  }
  printf("OpenGL: %s, %s\n", (const char *)glGetString(GL_VERSION),
         (const char *)glGetString(GL_RENDERER));

  memset(&options, 0, sizeof options);
  options.size = sizeof options;
  CADR_CHECK(cadr_context_options_default(&options));
  options.validation = test_dir != NULL;
  sample_print_messages();
  CADR_CHECK(cadr_context_create(&options, &context));
  CADR_CHECK(cadr_scene_create(&scene));
  CADR_CHECK(cadr_scene_root(scene, &root));
  memset(&loaded, 0, sizeof loaded);
  loaded.size = sizeof loaded;
  CADR_CHECK(cadr_scene_load(scene, source, root, &loaded));
  cadr_load_result_free(&loaded);
  CADR_CHECK(cadr_scene_bounds(scene, &bounds));

  /* The texture the frames go into, and a framebuffer to blit it from. */
  glGenTextures(1, &host.texture);
  glBindTexture(GL_TEXTURE_2D, host.texture);
  host.gl.TexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA8, WIDTH, HEIGHT);
  host.gl.GenFramebuffers(1, &host.framebuffer);
  host.gl.BindFramebuffer(GL_READ_FRAMEBUFFER, host.framebuffer);
  host.gl.FramebufferTexture2D(GL_READ_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D,
                               host.texture, 0);
  host.gl.BindFramebuffer(GL_READ_FRAMEBUFFER, 0);

  /* The shared path where both drivers allow it, else reading back. */
  if (!read_back_only && host.gl.ImportMemoryFdEXT != NULL &&
      cadr_renderer_create_for_export(context, WIDTH, HEIGHT, &renderer) == CADR_RESULT_OK) {
    if (!import_frames(&host, renderer)) {
      printf("the OpenGL driver refused cadr's memory: reading frames back instead\n");
      CADR_CHECK(cadr_renderer_destroy(renderer));
      renderer = NULL;
    }
  } else if (!read_back_only) {
    printf("shared memory unavailable (%s): reading frames back instead\n",
           host.gl.ImportMemoryFdEXT == NULL ? "no GL_EXT_memory_object_fd"
                                              : "cadr cannot export frames on this device");
  }
  if (renderer == NULL) {
    CADR_CHECK(cadr_renderer_create(context, WIDTH, HEIGHT, &renderer));
    host.pixels = (uint8_t *)malloc((size_t)WIDTH * HEIGHT * 4);
    if (host.pixels == NULL) {
      return 1;
    }
  }
  printf("path: %s\n", host.pixel_buffer != 0 ? "shared memory" : "read-back");

  memset(&stats, 0, sizeof stats);
  stats.size = sizeof stats;
  start = now_seconds();
  /* The window does not resize; a host whose view does calls cadr_renderer_resize and then
   * import_frames again (the frames go to new memory, of a new generation). */
  for (frame = 0; frame < frames && !glfwWindowShouldClose(window); ++frame) {
    orbit_camera(&bounds, 6.2831853 * frame / (frames > 0 ? frames : 1), &camera);
    CADR_CHECK(cadr_renderer_render(renderer, scene, &camera, &stats));
    read_back += show_frame(&host, renderer);
    glfwSwapBuffers(window);
    glfwPollEvents();
  }
  printf("%d frames, %.1f frames/s, bytes read back per frame: %zu\n", frame,
         frame / (now_seconds() - start), frame > 0 ? read_back / (size_t)frame : 0);

  if (test_dir != NULL) {
    char path[4096];
    char line[64];
    CadrRenderer offscreen;
    snprintf(path, sizeof path, "%s/offscreen.png", test_dir);
    CADR_CHECK(cadr_renderer_create(context, WIDTH, HEIGHT, &offscreen));
    CADR_CHECK(cadr_renderer_render(offscreen, scene, &camera, NULL));
    CADR_CHECK(cadr_renderer_save_png(offscreen, path));
    CADR_CHECK(cadr_renderer_destroy(offscreen));
    show_frame(&host, renderer);
    glfwSwapBuffers(window);
    glFinish();
    printf("screenshot ready %dx%d\n", WIDTH, HEIGHT);
    fflush(stdout);
    /* Keep the frame on the window until the test has grabbed it. */
    while (fgets(line, sizeof line, stdin) == NULL && !feof(stdin)) {
    }
  }
  CADR_CHECK(cadr_context_validation_error_count(context, &validation_errors));
  printf("validation errors: %llu\n", (unsigned long long)validation_errors);
  if (host.pixel_buffer != 0) {
    host.gl.DeleteBuffers(1, &host.pixel_buffer);
    host.gl.DeleteMemoryObjectsEXT(1, &host.memory_object);
  }
  host.gl.DeleteFramebuffers(1, &host.framebuffer);
  glDeleteTextures(1, &host.texture);
  free(host.pixels);
  CADR_CHECK(cadr_renderer_destroy(renderer));
  CADR_CHECK(cadr_scene_destroy(scene));
  CADR_CHECK(cadr_context_destroy(context));
  glfwDestroyWindow(window);
  glfwTerminate();
  return validation_errors == 0 ? 0 : 1;
}
