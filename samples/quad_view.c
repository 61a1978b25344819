/* Four views of one scene in one window, as a CAD tool shows them: top, front and side
 * (orthographic) and a perspective view, each a cadr renderer of the same scene on one context,
 * their frames brought into the OpenGL window through shared memory (common/gl_frames.c). A
 * click in a view picks there and highlights the part in all four; a click on the background
 * clears the selection.
 *
 *   quad_view [scene] [--frames N] [--views N] [--view-size WxH] [--self-test DIR]
 *
 * It orbits the perspective view for N frames (default 120) and prints each view's CPU time per
 * frame, the frames per second, cadr's device memory, its own host memory and the process's
 * heap. --views N shows only the first N views
 * (top, front, side, perspective), to compare one view's costs with four's; --view-size WxH
 * sets each view's size (default 320x240; the window holds two by two), so that one view of a
 * window's whole size can be compared with four quarters of it. --self-test DIR picks in the middle of
 * each view (printing what it found), writes the offscreen render of each view's camera
 * (DIR/view0.png ... view3.png), prints where each view lies in the window ("view N at X,Y
 * WxH") and "screenshot ready WxH", and keeps showing the views until a line arrives on stdin,
 * so that a test can grab the window and compare. */
#define _POSIX_C_SOURCE 199309L
#include <GLFW/glfw3.h>

#include "common/gl_frames.h"
#include "common/sample.h"

#include <malloc.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { VIEWS = 4 };
/* Each view's size (--view-size); the window holds two by two. */
static int view_width = 320, view_height = 240;

static const char *const view_names[VIEWS] = {"top", "front", "side", "perspective"};

struct QuadView {
  CadrScene scene;
  struct CadrBounds bounds;
  struct GlFrames views[VIEWS];
  struct CadrCamera cameras[VIEWS];
  double orbit;            /* the perspective view's angle about the up axis */
  CadrNode selected;       /* the highlighted geo node, 0 for none */
  int count;               /* the views shown: the first `count` of top, front, side, perspective */
  double cpu_us[VIEWS];    /* each view's CPU time, summed over the frames after the first */
  int timed_frames;        /* how many frames cpu_us sums */
};

static double now_seconds(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + (double)t.tv_nsec / 1e9;
}

/* An orthographic camera looking at the bounds' centre from `direction` (a unit axis; cadr's
 * look-at keeps +Y up, or +Z looking along Y), fitting the bounds: Vulkan's clip space (y down,
 * depth 0..1), as cadr's cameras. */
static void orthographic(const struct CadrBounds *b, const double direction[3],
                         struct CadrCamera *camera) {
  double center[3], eye[3], extent = 0.0, half_w, half_h, depth;
  int i;
  struct CadrCamera look;
  for (i = 0; i < 3; ++i) {
    double size = b->max[i] - b->min[i];
    center[i] = 0.5 * (b->min[i] + b->max[i]);
    extent += size * size;
  }
  extent = sqrt(extent) * 0.5 + 1e-9; /* the bounding sphere's radius */
  for (i = 0; i < 3; ++i) {
    eye[i] = center[i] + direction[i] * extent * 2.0;
  }
  /* The view matrix from cadr's look-at (its projection is replaced below). */
  CADR_CHECK(cadr_camera_look_at(eye, center, 45.0, (double)view_width / view_height, 0.1, 1.0, &look));
  memcpy(camera->view, look.view, sizeof camera->view);
  half_h = extent * 1.05;
  half_w = half_h * view_width / view_height;
  depth = extent * 4.0;
  memset(camera->projection, 0, sizeof camera->projection);
  camera->projection[0] = 1.0 / half_w;
  camera->projection[5] = -1.0 / half_h; /* y down */
  camera->projection[10] = -1.0 / depth; /* view -z from 0 to depth -> 0..1 */
  camera->projection[14] = 0.0;
  camera->projection[15] = 1.0;
}

/* The four views' cameras: top (looking down), front, side (from +X), and the orbiting
 * perspective view. */
static void place_cameras(struct QuadView *q) {
  const double top[3] = {0.0, 1.0, 0.0}, front[3] = {0.0, 0.0, 1.0}, side[3] = {1.0, 0.0, 0.0};
  const double around[3] = {cos(q->orbit), 0.6, sin(q->orbit)};
  orthographic(&q->bounds, top, &q->cameras[0]);
  orthographic(&q->bounds, front, &q->cameras[1]);
  orthographic(&q->bounds, side, &q->cameras[2]);
  CADR_CHECK(cadr_camera_fit(&q->bounds, (double)view_width / view_height, around, &q->cameras[3]));
}

/* Where view `index` lies in the window: its top-left corner. */
static void view_origin(int index, int *x, int *y) {
  *x = (index % 2) * view_width;
  *y = (index / 2) * view_height;
}

/* Renders every view and puts it in its quarter, adding each view's CPU time to `cpu_us` when
 * `timed`; returns the bytes read back. */
static size_t draw(struct QuadView *q, int timed) {
  size_t read_back = 0;
  int i;
  for (i = 0; i < q->count; ++i) {
    struct CadrFrameStats stats;
    int x, y;
    memset(&stats, 0, sizeof stats);
    stats.size = sizeof stats;
    gl_frames_render(&q->views[i], q->scene, &q->cameras[i], &stats);
    if (timed) {
      q->cpu_us[i] += stats.cpu_us;
    }
    view_origin(i, &x, &y);
    read_back += gl_frames_show(&q->views[i], x, y, (2 * view_height));
  }
  return read_back;
}

/* Picks at window pixel (x, y) in the view under it; highlights the part found in every view
 * (the highlight is the scene's) and returns its node, 0 over the background. */
static CadrNode select_at(struct QuadView *q, int x, int y) {
  int index = (y >= view_height ? 2 : 0) + (x >= view_width ? 1 : 0), origin_x, origin_y;
  CadrPickResult picked;
  if (index >= q->count) {
    return q->selected; /* an empty quarter */
  }
  memset(&picked, 0, sizeof picked);
  picked.size = sizeof picked;
  view_origin(index, &origin_x, &origin_y);
  CADR_CHECK(cadr_renderer_pick(q->views[index].renderer, q->scene, &q->cameras[index],
                                (uint32_t)(x - origin_x), (uint32_t)(y - origin_y), &picked));
  sample_set_highlighted(q->scene, q->selected, 0);
  q->selected = picked.hit_count > 0 ? picked.hits[0].node : 0;
  sample_set_highlighted(q->scene, q->selected, 1);
  printf("%s view: %s node %llu\n", view_names[index],
         picked.hit_count > 0 ? "picked" : "nothing under the cursor, cleared",
         (unsigned long long)q->selected);
  cadr_pick_result_free(&picked);
  return q->selected;
}

static void on_click(GLFWwindow *window, int button, int action, int mods) {
  struct QuadView *q = (struct QuadView *)glfwGetWindowUserPointer(window);
  double x, y;
  (void)mods;
  if (button == GLFW_MOUSE_BUTTON_LEFT && action == GLFW_PRESS) {
    glfwGetCursorPos(window, &x, &y);
    if (x >= 0 && y >= 0 && x < (2 * view_width) && y < (2 * view_height)) {
      select_at(q, (int)x, (int)y);
    }
  }
}

/* Bytes of the process's heap in use: cadr's, the drivers' (on lavapipe the "device" memory,
 * compiled shaders and the rasterizer's working memory live there too) and this program's. */
static uint64_t heap_bytes(void) {
  struct mallinfo2 info = mallinfo2();
  return (uint64_t)info.uordblks + (uint64_t)info.hblkhd;
}

/* The memory cadr holds: device memory, and its own host memory (without the drivers'). */
static struct CadrMemoryUsage memory_usage(CadrContext context) {
  struct CadrMemoryUsage usage;
  memset(&usage, 0, sizeof usage);
  usage.size = sizeof usage;
  CADR_CHECK(cadr_context_memory_usage(context, &usage));
  return usage;
}

/* Prints what one view and all the views hold, and their ratio. */
static void print_memory(const char *what, uint64_t one_view, int views, uint64_t all_views) {
  printf("%s memory: one view %.2f MB, %d views %.2f MB (%.3fx one view)\n", what,
         one_view / 1e6, views, all_views / 1e6,
         one_view > 0 ? (double)all_views / (double)one_view : 0.0);
}

/* Picks in the middle of each view, writes each view's offscreen render and keeps the window
 * until stdin says the test has grabbed it. */
static void self_test(struct QuadView *q, CadrContext context, GLFWwindow *window,
                      const char *dir) {
  char path[4096];
  int i;
  for (i = 0; i < q->count; ++i) {
    int x, y;
    view_origin(i, &x, &y);
    select_at(q, x + view_width / 2, y + view_height / 2);
  }
  /* The last pick's part stays highlighted in every view. */
  draw(q, 0);
  for (i = 0; i < q->count; ++i) {
    int x, y;
    snprintf(path, sizeof path, "%s/view%d.png", dir, i);
    sample_save_offscreen(context, q->scene, &q->cameras[i], view_width, view_height, path);
    view_origin(i, &x, &y);
    printf("view %d at %d,%d %dx%d\n", i, x, y, view_width, view_height);
  }
  glfwSwapBuffers(window);
  glFinish();
  sample_screenshot_ready((2 * view_width), (2 * view_height));
}

int main(int argc, char **argv) {
  const char *source = "gen:demo", *test_dir = NULL;
  int frames = 120, views = VIEWS, frame, i, shared = 1;
  struct QuadView q;
  CadrContext context;
  GLFWwindow *window;
  size_t read_back = 0;
  double start;
  struct CadrMemoryUsage before, one_view, all_views;
  uint64_t heap_before, one_view_heap, validation_errors = 0;

  for (i = 1; i < argc; ++i) {
    if (strcmp(argv[i], "--frames") == 0 && i + 1 < argc) {
      frames = atoi(argv[++i]);
    } else if (strcmp(argv[i], "--self-test") == 0 && i + 1 < argc) {
      test_dir = argv[++i];
    } else if (strcmp(argv[i], "--views") == 0 && i + 1 < argc) {
      views = atoi(argv[++i]);
    } else if (strcmp(argv[i], "--view-size") == 0 && i + 1 < argc) {
      if (sscanf(argv[++i], "%dx%d", &view_width, &view_height) != 2 || view_width < 16 ||
          view_height < 16 || view_width > 4096 || view_height > 4096) {
        fprintf(stderr, "quad_view: --view-size takes WxH, each 16 to 4096\n");
        return 2;
      }
    } else {
      source = argv[i];
    }
  }
  memset(&q, 0, sizeof q);
  if (views < 1 || views > VIEWS) {
    fprintf(stderr, "quad_view: --views takes 1 to %d\n", VIEWS);
    return 2;
  }
  q.count = views;
  window = gl_frames_window("quad_view", (2 * view_width), (2 * view_height),
                            "cadr: top, front, side, perspective");
  glfwSetWindowUserPointer(window, &q);
  glfwSetMouseButtonCallback(window, on_click);

  context = sample_context(NULL, 0, test_dir != NULL);
  q.scene = sample_load(source, &q.bounds);
  place_cameras(&q);

  /* What the views cost: the scene on the GPU (shared by the renderers of one scene) and each
   * view's targets, measured from before the first renderer. */
  before = memory_usage(context);
  heap_before = heap_bytes();
  memset(&one_view, 0, sizeof one_view);
  one_view_heap = 0;
  for (i = 0; i < q.count; ++i) {
    gl_frames_create(&q.views[i], context, view_width, view_height, 1);
    shared = shared && gl_frames_shared(&q.views[i]);
    if (i == 0) {
      struct CadrFrameStats stats;
      memset(&stats, 0, sizeof stats);
      stats.size = sizeof stats;
      gl_frames_render(&q.views[0], q.scene, &q.cameras[0], &stats);
      one_view = memory_usage(context);
      one_view_heap = heap_bytes() - heap_before;
    }
  }
  printf("path: %s\n", shared ? "shared memory" : "read-back");

  start = now_seconds();
  for (frame = 0; frame < frames && !glfwWindowShouldClose(window); ++frame) {
    q.orbit = 6.2831853 * frame / (frames > 0 ? frames : 1);
    place_cameras(&q);
    /* The first frame builds pipelines and uploads the scene: the CPU times leave it out. */
    read_back += draw(&q, frame > 0);
    q.timed_frames += frame > 0;
    glfwSwapBuffers(window);
    glfwPollEvents();
  }
  for (i = 0; i < q.count; ++i) {
    printf("%s view: %.1f us of CPU per frame\n", view_names[i],
           q.timed_frames > 0 ? q.cpu_us[i] / q.timed_frames : 0.0);
  }
  printf("%d frames of four views, %.1f frames/s, bytes read back per frame: %zu\n", frame,
         frame / (now_seconds() - start), frame > 0 ? read_back / (size_t)frame : 0);
  all_views = memory_usage(context);
  print_memory("device", one_view.device_allocated_bytes - before.device_allocated_bytes, q.count,
               all_views.device_allocated_bytes - before.device_allocated_bytes);
  print_memory("cadr's host", one_view.host_allocated_bytes - before.host_allocated_bytes,
               q.count, all_views.host_allocated_bytes - before.host_allocated_bytes);
  print_memory("process heap", one_view_heap, q.count, heap_bytes() - heap_before);

  if (test_dir != NULL) {
    self_test(&q, context, window, test_dir);
  }
  CADR_CHECK(cadr_context_validation_error_count(context, &validation_errors));
  printf("validation errors: %llu\n", (unsigned long long)validation_errors);
  for (i = 0; i < q.count; ++i) {
    gl_frames_destroy(&q.views[i]);
  }
  CADR_CHECK(cadr_scene_destroy(q.scene));
  CADR_CHECK(cadr_context_destroy(context));
  glfwDestroyWindow(window);
  glfwTerminate();
  return validation_errors == 0 ? 0 : 1;
}
