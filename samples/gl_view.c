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
#include <GLFW/glfw3.h>

#include "common/gl_frames.h"
#include "common/sample.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { WIDTH = 320, HEIGHT = 240 };

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
  struct GlFrames view;
  struct CadrContextOptions options;
  struct CadrBounds bounds;
  struct CadrCamera camera;
  CadrContext context;
  CadrScene scene;
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
  window = gl_frames_window("gl_view", WIDTH, HEIGHT, "cadr in OpenGL");

  memset(&options, 0, sizeof options);
  options.size = sizeof options;
  CADR_CHECK(cadr_context_options_default(&options));
  options.validation = test_dir != NULL;
  sample_print_messages();
  CADR_CHECK(cadr_context_create(&options, &context));
  scene = sample_load(source, &bounds);

  gl_frames_create(&view, context, WIDTH, HEIGHT, !read_back_only);
  printf("path: %s\n", gl_frames_shared(&view) ? "shared memory" : "read-back");
  start = now_seconds();
  for (frame = 0; frame < frames && !glfwWindowShouldClose(window); ++frame) {
    orbit_camera(&bounds, 6.2831853 * frame / (frames > 0 ? frames : 1), &camera);
    CADR_CHECK(cadr_renderer_render(view.renderer, scene, &camera, NULL));
    read_back += gl_frames_show(&view, 0, 0, HEIGHT);
    glfwSwapBuffers(window);
    glfwPollEvents();
  }
  printf("%d frames, %.1f frames/s, bytes read back per frame: %zu\n", frame,
         frame / (now_seconds() - start), frame > 0 ? read_back / (size_t)frame : 0);

  if (test_dir != NULL) {
    char path[4096];
    snprintf(path, sizeof path, "%s/offscreen.png", test_dir);
    sample_save_offscreen(context, scene, &camera, WIDTH, HEIGHT, path);
    /* The frame stays on the window until the test has grabbed it. */
    gl_frames_show(&view, 0, 0, HEIGHT);
    glfwSwapBuffers(window);
    glFinish();
    sample_screenshot_ready(WIDTH, HEIGHT);
  }
  CADR_CHECK(cadr_context_validation_error_count(context, &validation_errors));
  printf("validation errors: %llu\n", (unsigned long long)validation_errors);
  gl_frames_destroy(&view);
  CADR_CHECK(cadr_scene_destroy(scene));
  CADR_CHECK(cadr_context_destroy(context));
  glfwDestroyWindow(window);
  glfwTerminate();
  return validation_errors == 0 ? 0 : 1;
}
