/* An OpenGL host (a GLFW window with an OpenGL context, as the Open CASCADE viewer, VTK or Qt's
 * OpenGL widgets are) showing cadr's frames without copying them through the CPU: cadr copies
 * each frame on the GPU into memory it exports as a file descriptor
 * (cadr_renderer_create_for_export); the host imports that memory once as an OpenGL buffer
 * (GL_EXT_memory_object_fd), uploads the frame from it into a texture on the GPU, and blits the
 * texture into its window. Where the drivers cannot share memory, it reads each frame back
 * (cadr_renderer_read_pixels) and says so.
 *
 *   gl_view [scene] [--frames N] [--read-back] [--depth] [--self-test DIR]
 *
 * It orbits the scene for N frames (default 60) and prints which path it took, the bytes read
 * back through the CPU per frame and the frames per second. --read-back takes the read-back path
 * on purpose. --depth has cadr keep each frame's depth too (exported after the colour, or read
 * back with cadr_renderer_read_depth on the read-back path), and the host draws the world's
 * axes through the scene's centre into cadr's frame with OpenGL, hidden where cadr's parts are
 * in front of them (what a CAD tool does with its manipulators and grids). --self-test DIR
 * also writes the offscreen render of the last frame's camera (DIR/offscreen.png), prints
 * "screenshot ready WxH" and keeps showing that frame until a line arrives on stdin, so that a
 * test can grab the window and compare; with --depth it first checks the depth test against
 * cadr's depth over every pixel and prints "depth compositing: A of N pixels agree, R drawn
 * over". */
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

/* The world's axes through the centre of `bounds`, red, green and blue, drawn with OpenGL into
 * cadr's frame (its camera loaded, the depth test on). */
static void draw_axes(const struct CadrBounds *bounds) {
  double centre[3], reach = 0.0;
  int axis;
  for (axis = 0; axis < 3; ++axis) {
    centre[axis] = 0.5 * (bounds->min[axis] + bounds->max[axis]);
    reach += (bounds->max[axis] - bounds->min[axis]) * (bounds->max[axis] - bounds->min[axis]);
  }
  reach = 0.6 * sqrt(reach);
  glLineWidth(3.0f);
  glBegin(GL_LINES);
  for (axis = 0; axis < 3; ++axis) {
    double end[3] = {centre[0], centre[1], centre[2]};
    glColor3f(axis == 0, axis == 1, axis == 2);
    end[axis] -= reach;
    glVertex3dv(end);
    end[axis] += 2.0 * reach;
    glVertex3dv(end);
  }
  glEnd();
}

/* Draws a red rectangle over the whole frame at cadr's median depth with the depth test on, and
 * checks every pixel: red exactly where cadr's depth lies behind the rectangle. */
static void check_depth_compositing(struct GlFrames *view) {
  const size_t pixels = (size_t)view->width * view->height;
  float *depth = (float *)malloc(pixels * sizeof(float));
  float *covered = (float *)malloc(pixels * sizeof(float));
  unsigned char *rgba = (unsigned char *)malloc(pixels * 4);
  size_t i, count = 0, agree = 0, drawn_over = 0;
  float middle;
  if (depth == NULL || covered == NULL || rgba == NULL) {
    fprintf(stderr, "out of memory\n");
    exit(1);
  }
  gl_frames_update(view);
  gl_frames_read_depth(view, depth);
  for (i = 0; i < pixels; ++i) {
    if (depth[i] < 1.0f) {
      covered[count++] = depth[i];
    }
  }
  /* The median of the covered pixels' depths (a rough one: the middle of a partial sort). */
  middle = 0.5f;
  if (count > 0) {
    size_t a, b;
    for (a = 0; a <= count / 2; ++a) {
      for (b = a + 1; b < count; ++b) {
        if (covered[b] < covered[a]) {
          float t = covered[a];
          covered[a] = covered[b];
          covered[b] = t;
        }
      }
    }
    middle = covered[count / 2];
  }
  gl_frames_begin_drawing(view);
  glMatrixMode(GL_PROJECTION);
  glLoadIdentity();
  glMatrixMode(GL_MODELVIEW);
  glLoadIdentity();
  glColor3f(1.0f, 0.0f, 0.0f);
  glBegin(GL_QUADS);
  /* Window depth d is normalized depth 2d - 1 with OpenGL's default depth range. */
  glVertex3f(-1.0f, -1.0f, 2.0f * middle - 1.0f);
  glVertex3f(1.0f, -1.0f, 2.0f * middle - 1.0f);
  glVertex3f(1.0f, 1.0f, 2.0f * middle - 1.0f);
  glVertex3f(-1.0f, 1.0f, 2.0f * middle - 1.0f);
  glEnd();
  glReadPixels(0, 0, (GLsizei)view->width, (GLsizei)view->height, GL_RGBA, GL_UNSIGNED_BYTE,
               rgba);
  gl_frames_end_drawing();
  for (i = 0; i < pixels; ++i) {
    const unsigned char *p = &rgba[i * 4];
    const int red = p[0] == 255 && p[1] == 0 && p[2] == 0;
    drawn_over += (size_t)red;
    agree += (size_t)(red == (depth[i] > middle));
  }
  printf("depth compositing: %zu of %zu pixels agree, %zu drawn over (at depth %.4f)\n", agree,
         pixels, drawn_over, middle);
  free(rgba);
  free(covered);
  free(depth);
}

/* The scene's bounds seen from a direction turned `angle` about the up axis. */
static void orbit_camera(const struct CadrBounds *bounds, double angle, struct CadrCamera *camera) {
  const double direction[3] = {cos(angle), 0.6, sin(angle)};
  CADR_CHECK(cadr_camera_fit(bounds, (double)WIDTH / HEIGHT, direction, camera));
}

int main(int argc, char **argv) {
  const char *source = "gen:demo", *test_dir = NULL;
  int frames = 60, read_back_only = 0, with_depth = 0, frame, i;
  struct GlFrames view;
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
    } else if (strcmp(argv[i], "--depth") == 0) {
      with_depth = 1;
    } else if (strcmp(argv[i], "--self-test") == 0 && i + 1 < argc) {
      test_dir = argv[++i];
    } else {
      source = argv[i];
    }
  }
  window = gl_frames_window("gl_view", WIDTH, HEIGHT, "cadr in OpenGL");

  context = sample_context(NULL, 0, test_dir != NULL);
  scene = sample_load(source, &bounds);

  gl_frames_create(&view, context, WIDTH, HEIGHT,
                   (read_back_only ? 0 : GL_FRAMES_SHARE) | (with_depth ? GL_FRAMES_DEPTH : 0));
  printf("path: %s%s\n", gl_frames_shared(&view) ? "shared memory" : "read-back",
         gl_frames_has_depth(&view) ? ", with depth" : "");
  start = now_seconds();
  for (frame = 0; frame < frames && !glfwWindowShouldClose(window); ++frame) {
    orbit_camera(&bounds, 6.2831853 * frame / (frames > 0 ? frames : 1), &camera);
    gl_frames_render(&view, scene, &camera, NULL);
    read_back += gl_frames_update(&view);
    if (gl_frames_has_depth(&view)) {
      gl_frames_begin_drawing(&view);
      gl_frames_load_camera(&camera);
      draw_axes(&bounds);
      gl_frames_end_drawing();
    }
    gl_frames_blit(&view, 0, 0, HEIGHT);
    glfwSwapBuffers(window);
    glfwPollEvents();
  }
  printf("%d frames, %.1f frames/s, bytes read back per frame: %zu\n", frame,
         frame / (now_seconds() - start), frame > 0 ? read_back / (size_t)frame : 0);

  if (test_dir != NULL) {
    char path[4096];
    snprintf(path, sizeof path, "%s/offscreen.png", test_dir);
    sample_save_offscreen(context, scene, &camera, WIDTH, HEIGHT, path);
    if (gl_frames_has_depth(&view)) {
      check_depth_compositing(&view);
    }
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
