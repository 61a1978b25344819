/* viewer: a GLFW window showing a scene through cadr's swapchain.
 *
 *   viewer [scene]                   (default gen:demo; .gltf/.glb/.csf/.csf.gz or gen:NAME)
 *   viewer [scene] --self-test DIR   scripted run for the tests (see below)
 *   viewer [scene] [--frames-in-flight 1|2|3] [--present fifo|mailbox|immediate]
 *                  [--msaa N] [--orbit-frames N]
 *
 * Mouse: left drag orbits, right or middle drag pans, the wheel zooms; a left click selects
 *        the part under the cursor (highlighted; a click on the background clears it).
 * Keys:  V, P, S, C cycle the vertex path, parameter path, submission and culling technique;
 *        E cycles the display modes (solid, edges, hidden-line, wireframe, xray); T cycles the
 *        transparency methods; F fits the view; I cycles 1 / 2 / 3 frames in flight;
 *        M cycles the present modes the window offers; X cycles a section plane through the
 *        view's centre across x, y, z and off; K toggles its caps, H their hatching;
 *        D toggles dashed hidden edges in hidden-line; O toggles ambient occlusion;
 *        U toggles materials' textures; L toggles silhouette edges in edges, hidden-line and xray;
 *        G cycles the highlight style (tint, outline);
 *        B cycles the background (cadr's gradient, white, dark with light edge lines);
 *        A cycles the anti-aliasing levels the device offers (MSAA 2x, 4x, 8x, then off);
 *        Esc quits.
 * The window title shows the techniques, the section, the anti-aliasing, frames in flight, present mode, the frame's figures
 * and frames per second; they are also printed once a second. --orbit-frames N orbits the
 * camera for N frames as fast as they come, prints the frames per second and quits (a
 * benchmark of the window path). Resizing and minimizing are handled by cadr (swapchain recreated, frames skipped).
 *
 * --self-test DIR renders frames, cycles every technique kind once, toggles the shade mode,
 * cycles the section planes with and without caps and hatching, cycles the backgrounds and
 * the anti-aliasing levels (in X-ray and with edges too),
 * resizes the window, then renders a fixed view both into the window and offscreen
 * (DIR/offscreen.png), prints "screenshot ready WxH" and keeps presenting until a line arrives
 * on stdin, so that a test can grab the window and compare. */
#define _POSIX_C_SOURCE 199309L
#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>

#include "common/sample.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static const char *const kind_names[5] = {"vertex", "params", "submit", "cull", "transparency"};

struct Viewer {
  GLFWwindow *window;
  CadrContext context;
  CadrScene scene;
  CadrRenderer renderer;
  struct CadrBounds bounds;
  double target[3], distance, yaw, pitch, radius;
  double last_x, last_y;
  int dragging; /* 0 none, 1 orbit, 2 pan */
  double press_x, press_y; /* where the left button went down: a click if it comes up there */
  CadrNode selected;       /* the highlighted geo node, 0 for none */
  CadrRendererSettings settings; /* what the keys change, applied with apply_settings */
  int section_axis;      /* -1: no section; 0, 1, 2: a plane across x, y or z */
  uint32_t background;    /* index into backgrounds */
  struct CadrFrameStats stats;
  double frames_per_second;
};

static const char *const present_names[3] = {"fifo", "mailbox", "immediate"};

static double now_seconds(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + (double)t.tv_nsec / 1e9;
}

static void fit_view(struct Viewer *v) {
  int axis;
  double extent = 0;
  for (axis = 0; axis < 3; ++axis) {
    double size = v->bounds.max[axis] - v->bounds.min[axis];
    v->target[axis] = size >= 0 ? 0.5 * (v->bounds.min[axis] + v->bounds.max[axis]) : 0.0;
    extent += size >= 0 ? size * size : 0.0;
  }
  v->radius = extent > 0 ? 0.5 * sqrt(extent) : 1.0;
  v->distance = v->radius / sin(0.5 * 40.0 * 3.14159265358979 / 180.0) * 1.05;
  v->yaw = 0.6;
  v->pitch = 0.45;
}

static void camera_of(const struct Viewer *v, uint32_t width, uint32_t height,
                      struct CadrCamera *camera) {
  double eye[3];
  eye[0] = v->target[0] + v->distance * cos(v->pitch) * sin(v->yaw);
  eye[1] = v->target[1] + v->distance * sin(v->pitch);
  eye[2] = v->target[2] + v->distance * cos(v->pitch) * cos(v->yaw);
  CADR_CHECK(cadr_camera_look_at(eye, v->target, 40.0, (double)width / (height ? height : 1),
                                 v->distance * 1e-3, v->distance + 4.0 * v->radius, camera));
}

/* Switches the technique of `kind` to the next one (in the context's list) that the device can
 * run and that fits the other three; prints what it chose or why none did. */
static void cycle_technique(struct Viewer *v, uint32_t kind) {
  const char *current = NULL;
  uint32_t count = 0, i, start = 0, step;
  struct CadrTechniqueInfo info = {.size = sizeof(struct CadrTechniqueInfo)};
  CADR_CHECK(cadr_renderer_technique(v->renderer, kind, &current));
  CADR_CHECK(cadr_context_technique_count(v->context, &count));
  for (i = 0; i < count; ++i) {
    CADR_CHECK(cadr_context_technique(v->context, i, &info));
    if (info.kind == (enum CadrTechniqueKind)kind && strcmp(info.name, current) == 0) {
      start = i;
    }
  }
  for (step = 1; step <= count; ++step) {
    CADR_CHECK(cadr_context_technique(v->context, (start + step) % count, &info));
    if (info.kind != (enum CadrTechniqueKind)kind || !info.supported) {
      continue;
    }
    if (cadr_renderer_set_technique(v->renderer, kind, info.name) == CADR_RESULT_OK) {
      printf("%s technique: %s\n", kind_names[kind], info.name);
      return;
    }
  }
  printf("%s technique: no other one fits the current combination\n", kind_names[kind]);
}

static const char *const shade_names[5] = {"solid", "edges", "hidden-line", "wireframe", "xray"};

/* Applies the viewer's settings; a refused one is printed and the renderer's are read back
 * (cadr applies all of them or none). Returns whether they were applied. */
static int apply_settings(struct Viewer *v) {
  if (cadr_renderer_apply_settings(v->renderer, &v->settings) != CADR_RESULT_OK) {
    char message[512];
    size_t length = 0;
    if (cadr_last_error_message(message, sizeof message, &length) != CADR_RESULT_OK) {
      strcpy(message, "(message too long)");
    }
    printf("refused: %s\n", message);
    CADR_CHECK(cadr_renderer_settings(v->renderer, &v->settings));
    return 0;
  }
  return 1;
}

static void toggle_shade(struct Viewer *v) {
  v->settings.shade_mode = (v->settings.shade_mode + 1) % 5;
  if (apply_settings(v)) {
    printf("display mode: %s\n", shade_names[v->settings.shade_mode]);
  }
}

static const char *const axis_names[3] = {"x", "y", "z"};

/* Sets the section: a plane through the view's centre keeping the side below it on the axis. */
static void apply_section(struct Viewer *v) {
  double plane[4] = {0.0, 0.0, 0.0, 0.0};
  if (v->section_axis < 0) {
    CADR_CHECK(cadr_renderer_set_section_planes(v->renderer, NULL, 0));
  } else {
    plane[v->section_axis] = -1.0;
    plane[3] = v->target[v->section_axis];
    CADR_CHECK(cadr_renderer_set_section_planes(v->renderer, plane, 1));
  }
}

static void cycle_section(struct Viewer *v) {
  v->section_axis = v->section_axis >= 2 ? -1 : v->section_axis + 1;
  apply_section(v);
  printf("section: %s\n", v->section_axis < 0 ? "off" : axis_names[v->section_axis]);
}

static void toggle_section_flag(struct Viewer *v, uint32_t flag, const char *name) {
  v->settings.section_flags ^= flag;
  if (apply_settings(v)) {
    printf("section %s: %s\n", name, (v->settings.section_flags & flag) ? "on" : "off");
  }
}

/* The backgrounds B cycles through: cadr's default gradient first (read from the renderer).
 * The dark one comes with light edge lines, which dark lines would not show on. */
static const char *const background_names[3] = {"gradient", "white", "dark"};

static void cycle_background(struct Viewer *v) {
  static float default_top[3], default_bottom[3], default_edges[3];
  static int have_default = 0;
  static const float white[3] = {1.0f, 1.0f, 1.0f};
  static const float dark_top[3] = {0.20f, 0.22f, 0.26f}, dark_bottom[3] = {0.05f, 0.06f, 0.08f};
  static const float light_edges[3] = {0.85f, 0.87f, 0.90f};
  const float *top, *bottom;
  if (!have_default) {
    memcpy(default_top, v->settings.background_top, sizeof default_top);
    memcpy(default_bottom, v->settings.background_bottom, sizeof default_bottom);
    memcpy(default_edges, v->settings.edge_color, sizeof default_edges);
    have_default = 1;
  }
  v->background = (v->background + 1) % 3;
  top = v->background == 0 ? default_top : v->background == 1 ? white : dark_top;
  bottom = v->background == 0 ? default_bottom : v->background == 1 ? white : dark_bottom;
  memcpy(v->settings.background_top, top, sizeof v->settings.background_top);
  memcpy(v->settings.background_bottom, bottom, sizeof v->settings.background_bottom);
  memcpy(v->settings.edge_color, v->background == 2 ? light_edges : default_edges,
         sizeof v->settings.edge_color);
  if (apply_settings(v)) {
    printf("background: %s\n", background_names[v->background]);
  }
}

/* The next anti-aliasing level the device offers after the current one, off after the highest. */
static void cycle_msaa(struct Viewer *v) {
  CadrRendererCapabilities capabilities = {.size = sizeof(struct CadrRendererCapabilities)};
  uint32_t next;
  memset(&capabilities, 0, sizeof capabilities);
  capabilities.size = sizeof capabilities;
  capabilities.size = sizeof capabilities;
  CADR_CHECK(cadr_renderer_capabilities(v->renderer, &capabilities));
  for (next = v->settings.msaa_samples * 2;
       next <= 64 && !(capabilities.msaa_sample_counts & next); next *= 2) {
  }
  v->settings.msaa_samples = next > 64 ? 1 : next;
  if (apply_settings(v)) {
    next = v->settings.msaa_samples;
    printf("anti-aliasing: %s%u%s\n", next > 1 ? "MSAA " : "", next, next > 1 ? "x" : " sample (off)");
  }
}

/* Flips a yes/no setting and prints its new state. */
static void toggle(struct Viewer *v, bool *setting, const char *name, const char *on,
                   const char *off) {
  *setting = !*setting;
  if (apply_settings(v)) {
    printf("%s: %s\n", name, *setting ? on : off);
  }
}

static void toggle_dashed(struct Viewer *v) {
  toggle(v, &v->settings.dashed_hidden_lines, "hidden edges", "dashed", "removed");
}

static void toggle_textures(struct Viewer *v) {
  toggle(v, &v->settings.textures, "textures", "on", "off");
}

static void toggle_silhouettes(struct Viewer *v) {
  toggle(v, &v->settings.silhouettes, "silhouettes", "on", "off");
}

static void cycle_highlight_style(struct Viewer *v) {
  v->settings.highlight_style = v->settings.highlight_style == CADR_HIGHLIGHT_TINT
                                    ? CADR_HIGHLIGHT_OUTLINE
                                    : CADR_HIGHLIGHT_TINT;
  if (apply_settings(v)) {
    printf("highlight style: %s\n",
           v->settings.highlight_style == CADR_HIGHLIGHT_TINT ? "tint" : "outline");
  }
}

/* Selects the part under the window point (x, y) in screen coordinates: its geo node is
 * highlighted and the one selected before is not; over the background, nothing is selected. */
static void select_at(struct Viewer *v, double x, double y) {
  int window_width, window_height, fb_width, fb_height;
  uint32_t width = 0, height = 0;
  struct CadrCamera camera;
  CadrPickResult picked = {sizeof(struct CadrPickResult), NULL, 0};
  double px, py;
  glfwGetWindowSize(v->window, &window_width, &window_height);
  glfwGetFramebufferSize(v->window, &fb_width, &fb_height);
  CADR_CHECK(cadr_renderer_size(v->renderer, &width, &height));
  if (window_width <= 0 || window_height <= 0 || width == 0 || height == 0) {
    return;
  }
  /* Screen coordinates to pixels (they differ on high-density displays). */
  px = x * fb_width / window_width;
  py = y * fb_height / window_height;
  if (px < 0 || py < 0 || px >= width || py >= height) {
    return;
  }
  camera_of(v, width, height, &camera);
  CADR_CHECK(cadr_renderer_pick(v->renderer, v->scene, &camera, (uint32_t)px, (uint32_t)py, &picked));
  sample_set_highlighted(v->scene, v->selected, 0);
  v->selected = picked.hit_count > 0 ? picked.hits[0].node : 0;
  sample_set_highlighted(v->scene, v->selected, 1);
  if (picked.hit_count > 0) {
    printf("selected node %llu, part %u\n", (unsigned long long)v->selected, picked.hits[0].part);
  } else {
    printf("selection cleared\n");
  }
  cadr_pick_result_free(&picked);
}

static void toggle_ssao(struct Viewer *v) {
  toggle(v, &v->settings.ssao, "ambient occlusion", "on", "off");
}

static void toggle_frames_in_flight(struct Viewer *v) {
  v->settings.frames_in_flight = v->settings.frames_in_flight % 3 + 1;
  if (apply_settings(v)) {
    printf("frames in flight: %u\n", v->settings.frames_in_flight);
  }
}

/* The present modes the window offers: bit 1 << CADR_PRESENT_* for each. */
static uint32_t offered_present_modes(struct Viewer *v) {
  CadrRendererCapabilities capabilities = {.size = sizeof(struct CadrRendererCapabilities)};
  memset(&capabilities, 0, sizeof capabilities);
  capabilities.size = sizeof capabilities;
  capabilities.size = sizeof capabilities;
  CADR_CHECK(cadr_renderer_capabilities(v->renderer, &capabilities));
  return capabilities.present_modes;
}

/* The next present mode the window offers after the current one. */
static void cycle_present_mode(struct Viewer *v) {
  uint32_t offered = offered_present_modes(v), step;
  for (step = 1; step <= 3; ++step) {
    uint32_t next = (v->settings.present_mode + step) % 3;
    if (offered & (1u << next)) {
      v->settings.present_mode = next;
      if (apply_settings(v)) {
        printf("present mode: %s\n", present_names[next]);
      }
      return;
    }
  }
}

static void describe(struct Viewer *v, char *text, size_t size) {
  const char *names[5];
  char section[64];
  char antialiasing[24];
  const CadrRendererSettings *settings = &v->settings;
  uint32_t kind, samples = settings->msaa_samples, shade = settings->shade_mode;
  for (kind = 0; kind < 5; ++kind) {
    CADR_CHECK(cadr_renderer_technique(v->renderer, kind, &names[kind]));
  }
  if (samples > 1) {
    snprintf(antialiasing, sizeof antialiasing, "MSAA %ux", samples);
  } else {
    snprintf(antialiasing, sizeof antialiasing, "no AA");
  }
  snprintf(section, sizeof section, "%s%s%s",
           v->section_axis < 0 ? "no section" : "section ",
           v->section_axis < 0 ? "" : axis_names[v->section_axis],
           v->section_axis < 0 ? ""
           : (settings->section_flags & CADR_SECTION_CAPS)
               ? ((settings->section_flags & CADR_SECTION_HATCHED) ? " capped, hatched" : " capped")
               : " uncapped");
  snprintf(text, size,
           "cadr viewer | %s / %s / %s / %s | %s%s, %s highlight, %s | %s | %s | %s | %s background | %u in flight, %s | %llu draws in %llu calls | CPU %.0f us, GPU %.0f us | %.0f frames/s",
           names[0], names[1], names[2], names[3], shade_names[shade % 5],
           settings->silhouettes || (shade != CADR_SHADE_EDGES && shade != CADR_SHADE_HIDDEN_LINE && shade != CADR_SHADE_XRAY) ? "" : " without silhouettes",
           settings->highlight_style == CADR_HIGHLIGHT_OUTLINE ? "outline" : "tint",
           names[4],
           antialiasing, settings->textures ? "textures" : "no textures", section, background_names[v->background % 3], settings->frames_in_flight, present_names[settings->present_mode % 3], (unsigned long long)v->stats.draws,
           (unsigned long long)v->stats.draw_calls, v->stats.cpu_us, v->stats.gpu_us,
           v->frames_per_second);
}

static void render(struct Viewer *v) {
  uint32_t width = 0, height = 0;
  struct CadrCamera camera;
  CADR_CHECK(cadr_renderer_size(v->renderer, &width, &height));
  if (width == 0 || height == 0) {
    /* Minimized: cadr skips the frame; ask again after the next events. */
    width = height = 1;
  }
  camera_of(v, width, height, &camera);
  CADR_CHECK(cadr_renderer_render(v->renderer, v->scene, &camera, &v->stats));
}

static void on_key(GLFWwindow *window, int key, int scancode, int action, int mods) {
  struct Viewer *v = (struct Viewer *)glfwGetWindowUserPointer(window);
  (void)scancode;
  (void)mods;
  if (action != GLFW_PRESS) {
    return;
  }
  switch (key) {
  case GLFW_KEY_V: cycle_technique(v, CADR_TECHNIQUE_KIND_VERTEX); break;
  case GLFW_KEY_P: cycle_technique(v, CADR_TECHNIQUE_KIND_PARAMETERS); break;
  case GLFW_KEY_S: cycle_technique(v, CADR_TECHNIQUE_KIND_SUBMISSION); break;
  case GLFW_KEY_C: cycle_technique(v, CADR_TECHNIQUE_KIND_CULLING); break;
  case GLFW_KEY_T: cycle_technique(v, CADR_TECHNIQUE_KIND_TRANSPARENCY); break;
  case GLFW_KEY_E: toggle_shade(v); break;
  case GLFW_KEY_F: fit_view(v); break;
  case GLFW_KEY_I: toggle_frames_in_flight(v); break;
  case GLFW_KEY_M: cycle_present_mode(v); break;
  case GLFW_KEY_X: cycle_section(v); break;
  case GLFW_KEY_K: toggle_section_flag(v, CADR_SECTION_CAPS, "caps"); break;
  case GLFW_KEY_H: toggle_section_flag(v, CADR_SECTION_HATCHED, "hatching"); break;
  case GLFW_KEY_B: cycle_background(v); break;
  case GLFW_KEY_A: cycle_msaa(v); break;
  case GLFW_KEY_D: toggle_dashed(v); break;
  case GLFW_KEY_O: toggle_ssao(v); break;
  case GLFW_KEY_U: toggle_textures(v); break;
  case GLFW_KEY_L: toggle_silhouettes(v); break;
  case GLFW_KEY_G: cycle_highlight_style(v); break;
  case GLFW_KEY_ESCAPE: glfwSetWindowShouldClose(window, GLFW_TRUE); break;
  default: break;
  }
}

static void on_button(GLFWwindow *window, int button, int action, int mods) {
  struct Viewer *v = (struct Viewer *)glfwGetWindowUserPointer(window);
  (void)mods;
  if (action == GLFW_PRESS) {
    glfwGetCursorPos(window, &v->last_x, &v->last_y);
    v->press_x = v->last_x;
    v->press_y = v->last_y;
    v->dragging = button == GLFW_MOUSE_BUTTON_LEFT ? 1 : 2;
  } else {
    double x, y;
    glfwGetCursorPos(window, &x, &y);
    if (button == GLFW_MOUSE_BUTTON_LEFT && fabs(x - v->press_x) < 3 && fabs(y - v->press_y) < 3) {
      select_at(v, x, y);
    }
    v->dragging = 0;
  }
}

static void on_cursor(GLFWwindow *window, double x, double y) {
  struct Viewer *v = (struct Viewer *)glfwGetWindowUserPointer(window);
  double dx = x - v->last_x, dy = y - v->last_y;
  v->last_x = x;
  v->last_y = y;
  if (v->dragging == 1) {
    v->yaw -= dx * 0.01;
    v->pitch += dy * 0.01;
    if (v->pitch > 1.5) v->pitch = 1.5;
    if (v->pitch < -1.5) v->pitch = -1.5;
  } else if (v->dragging == 2) {
    /* Pan in the view plane: right = (cos yaw, 0, -sin yaw), up ~ world Y. */
    double scale = v->distance * 0.0015;
    v->target[0] -= (cos(v->yaw) * dx) * scale;
    v->target[2] -= (-sin(v->yaw) * dx) * scale;
    v->target[1] += dy * scale;
  }
}

static void on_scroll(GLFWwindow *window, double dx, double dy) {
  struct Viewer *v = (struct Viewer *)glfwGetWindowUserPointer(window);
  (void)dx;
  v->distance *= pow(0.9, dy);
  if (v->distance < v->radius * 1e-3) v->distance = v->radius * 1e-3;
}

static void on_framebuffer_size(GLFWwindow *window, int width, int height) {
  struct Viewer *v = (struct Viewer *)glfwGetWindowUserPointer(window);
  CADR_CHECK(cadr_renderer_resize(v->renderer, (uint32_t)width, (uint32_t)height));
}

/* The scripted run of --self-test. */
static int self_test(struct Viewer *v, const char *dir) {
  uint32_t kind, width = 0, height = 0;
  int frame, fb_width = 0, fb_height = 0;
  char path[1024];
  struct CadrCamera camera;
  uint64_t errors = 0;
  for (frame = 0; frame < 3; ++frame) {
    glfwPollEvents();
    render(v);
  }
  printf("rendered 3 frames: %llu draws, CPU %.1f us\n", (unsigned long long)v->stats.draws,
         v->stats.cpu_us);
  for (kind = 0; kind < 5; ++kind) {
    cycle_technique(v, kind);
    render(v);
  }
  for (frame = 0; frame < 5; ++frame) {
    toggle_shade(v);
    render(v);
  }
  /* A click at the window's centre selects the part there; each highlight style shows it;
   * a click outside the picture keeps it, one on the corner (background) clears it. */
  {
    int window_width = 0, window_height = 0;
    glfwGetWindowSize(v->window, &window_width, &window_height);
    select_at(v, window_width / 2.0, window_height / 2.0);
    if (v->selected == 0) {
      fprintf(stderr, "a click at the window's centre selected nothing\n");
      return 1;
    }
    render(v);
    cycle_highlight_style(v);
    render(v);
    cycle_highlight_style(v);
    select_at(v, 1.0, 1.0);
    render(v);
  }
  /* Each section axis, capped, hatched and uncapped, then off again. */
  for (frame = 0; frame < 4; ++frame) {
    cycle_section(v);
    render(v);
  }
  toggle_section_flag(v, CADR_SECTION_HATCHED, "hatching");
  cycle_section(v);
  render(v);
  toggle_section_flag(v, CADR_SECTION_CAPS, "caps");
  render(v);
  toggle_section_flag(v, CADR_SECTION_CAPS, "caps");
  toggle_section_flag(v, CADR_SECTION_HATCHED, "hatching");
  /* Every background, ending on the default. */
  for (frame = 0; frame < 3; ++frame) {
    cycle_background(v);
    render(v);
  }
  cycle_section(v);
  cycle_section(v);
  cycle_section(v);
  /* Every anti-aliasing level the device offers, in X-ray and with edges (its line and
   * translucent passes), ending without. */
  {
    uint32_t samples = 1, mode;
    do {
      cycle_msaa(v);
      for (mode = 0; mode < 5; ++mode) {
        toggle_shade(v);
        if (v->settings.shade_mode == CADR_SHADE_EDGES || v->settings.shade_mode == CADR_SHADE_XRAY) {
          render(v);
          toggle_ssao(v);
          render(v);
          toggle_ssao(v);
          toggle_textures(v);
          render(v);
          toggle_textures(v);
        } else if (v->settings.shade_mode == CADR_SHADE_HIDDEN_LINE) {
          toggle_dashed(v);
          render(v);
          toggle_dashed(v);
          toggle_silhouettes(v);
          render(v);
          toggle_silhouettes(v);
        }
      }
      samples = v->settings.msaa_samples;
    } while (samples > 1);
  }
  /* Every present mode the window offers, with one, two and three frames in flight. */
  {
    uint32_t mode, offered = offered_present_modes(v), frames;
    printf("present modes offered:");
    for (mode = 0; mode < 3; ++mode) {
      if (offered & (1u << mode)) {
        printf(" %s", present_names[mode]);
        for (frames = 1; frames <= 3; ++frames) {
          v->settings.frames_in_flight = frames;
          v->settings.present_mode = mode;
          CADR_CHECK(cadr_renderer_apply_settings(v->renderer, &v->settings));
          render(v);
          render(v);
        }
      }
    }
    printf("\n");
    v->settings.present_mode = CADR_PRESENT_FIFO;
    CADR_CHECK(cadr_renderer_apply_settings(v->renderer, &v->settings));
  }
  glfwSetWindowSize(v->window, 480, 360);
  for (frame = 0; frame < 200 && (fb_width != 480 || fb_height != 360); ++frame) {
    glfwPollEvents();
    glfwGetFramebufferSize(v->window, &fb_width, &fb_height);
  }
  /* The callback may not have run yet: tell the renderer directly as well. */
  CADR_CHECK(cadr_renderer_resize(v->renderer, (uint32_t)fb_width, (uint32_t)fb_height));
  render(v);
  CADR_CHECK(cadr_renderer_size(v->renderer, &width, &height));
  printf("resized to %ux%u\n", width, height);
  if (width != 480 || height != 360) {
    fprintf(stderr, "the swapchain is %ux%u after resizing the window to 480x360\n", width, height);
    return 1;
  }
  render(v);
  /* The same view, offscreen. */
  camera_of(v, width, height, &camera);
  snprintf(path, sizeof path, "%s/offscreen.png", dir);
  sample_save_offscreen(v->context, v->scene, &camera, width, height, path);
  /* Keep the window's content current while the test grabs it. */
  render(v);
  sample_screenshot_ready(width, height);
  CADR_CHECK(cadr_context_validation_error_count(v->context, &errors));
  printf("validation errors: %llu\n", (unsigned long long)errors);
  return errors == 0 ? 0 : 1;
}

int main(int argc, char **argv) {
  struct Viewer v;
  struct CadrLoadResult loaded = {.size = sizeof(struct CadrLoadResult)};
  const char *source = "gen:demo", *test_dir = NULL, **extensions;
  uint32_t extension_count = 0;
  void *instance = NULL;
  VkSurfaceKHR surface = VK_NULL_HANDLE;
  CadrNode root;
  int i, width, height, status = 0, orbit_frames = 0, frames_in_flight = 0, present = -1, msaa = 0;
  double last_print;
  char title[512];

  for (i = 1; i < argc; ++i) {
    if (strcmp(argv[i], "--self-test") == 0 && i + 1 < argc) {
      test_dir = argv[++i];
    } else if (strcmp(argv[i], "--orbit-frames") == 0 && i + 1 < argc) {
      orbit_frames = atoi(argv[++i]);
    } else if (strcmp(argv[i], "--msaa") == 0 && i + 1 < argc) {
      msaa = atoi(argv[++i]);
    } else if (strcmp(argv[i], "--frames-in-flight") == 0 && i + 1 < argc) {
      frames_in_flight = atoi(argv[++i]);
    } else if (strcmp(argv[i], "--present") == 0 && i + 1 < argc) {
      const char *name = argv[++i];
      for (present = 2; present >= 0 && strcmp(present_names[present], name) != 0; --present) {
      }
      if (present < 0) {
        fprintf(stderr, "viewer: --present %s: expected fifo, mailbox or immediate\n", name);
        return 2;
      }
    } else if (argv[i][0] == '-') {
      fprintf(stderr, "viewer: unknown option %s\n", argv[i]);
      return 2;
    } else {
      source = argv[i];
    }
  }
  memset(&v, 0, sizeof v);
  v.stats.size = sizeof v.stats;
  v.section_axis = -1;
  if (!glfwInit()) {
    fprintf(stderr, "viewer: GLFW cannot open a display (is DISPLAY set?)\n");
    return 1;
  }
  if (!glfwVulkanSupported()) {
    fprintf(stderr, "viewer: GLFW finds no Vulkan loader\n");
    return 1;
  }
  glfwWindowHint(GLFW_CLIENT_API, GLFW_NO_API);
  v.window = glfwCreateWindow(960, 640, "cadr viewer", NULL, NULL);
  if (v.window == NULL) {
    fprintf(stderr, "viewer: cannot create a window\n");
    return 1;
  }
  glfwSetWindowPos(v.window, 0, 0);

  /* A context with the window system's instance extensions. */
  extensions = glfwGetRequiredInstanceExtensions(&extension_count);
  v.context = sample_context(extensions, extension_count, test_dir != NULL);
  CADR_CHECK(cadr_context_vulkan_instance(v.context, &instance));
  if (glfwCreateWindowSurface((VkInstance)instance, v.window, NULL, &surface) != VK_SUCCESS) {
    fprintf(stderr, "viewer: cannot create a Vulkan surface for the window\n");
    return 1;
  }
  glfwGetFramebufferSize(v.window, &width, &height);
  CADR_CHECK(cadr_renderer_create_for_surface(v.context, (uint64_t)surface, (uint32_t)width,
                                              (uint32_t)height, &v.renderer));
  v.settings.size = sizeof v.settings;
  CADR_CHECK(cadr_renderer_settings(v.renderer, &v.settings));
  if (frames_in_flight != 0) {
    v.settings.frames_in_flight = (uint32_t)frames_in_flight;
  }
  if (present >= 0) {
    v.settings.present_mode = (uint32_t)present;
  }
  if (msaa != 0) {
    v.settings.msaa_samples = (uint32_t)msaa;
  }
  CADR_CHECK(cadr_renderer_apply_settings(v.renderer, &v.settings));

  CADR_CHECK(cadr_scene_create(&v.scene));
  CADR_CHECK(cadr_scene_root(v.scene, &root));
  CADR_CHECK(cadr_scene_load(v.scene, source, root, &loaded));
  cadr_load_result_free(&loaded);
  CADR_CHECK(cadr_scene_bounds(v.scene, &v.bounds));
  fit_view(&v);

  glfwSetWindowUserPointer(v.window, &v);
  glfwSetKeyCallback(v.window, on_key);
  glfwSetMouseButtonCallback(v.window, on_button);
  glfwSetCursorPosCallback(v.window, on_cursor);
  glfwSetScrollCallback(v.window, on_scroll);
  glfwSetFramebufferSizeCallback(v.window, on_framebuffer_size);
  printf("viewer: %s (V/P/S/C cycle techniques, E display mode, X section, K caps, H hatching, "
         "A anti-aliasing, D dashed hidden edges, O ambient occlusion, F fit, I frames in flight, M present mode, Esc quit)\n",
         source);

  if (test_dir != NULL) {
    status = self_test(&v, test_dir);
  } else if (orbit_frames > 0) {
    int frame;
    double start;
    render(&v); /* first-use costs (pipelines, uploads) are not counted */
    start = now_seconds();
    for (frame = 0; frame < orbit_frames; ++frame) {
      glfwPollEvents();
      v.yaw += 2.0 * 3.14159265358979 / 120.0; /* a 120th of a turn per frame */
      render(&v);
    }
    v.frames_per_second = orbit_frames / (now_seconds() - start);
    describe(&v, title, sizeof title);
    printf("%s\norbit: %d frames, %.1f frames/s\n", title, orbit_frames, v.frames_per_second);
  } else {
    int frames = 0;
    last_print = now_seconds();
    while (!glfwWindowShouldClose(v.window)) {
      glfwPollEvents();
      render(&v);
      ++frames;
      if (now_seconds() - last_print >= 1.0) {
        v.frames_per_second = frames / (now_seconds() - last_print);
        describe(&v, title, sizeof title);
        glfwSetWindowTitle(v.window, title);
        printf("%s\n", title);
        frames = 0;
        last_print = now_seconds();
      }
      if (!v.stats.presented) {
        glfwWaitEventsTimeout(0.05); /* minimized: sleep instead of spinning */
      }
    }
  }
  CADR_CHECK(cadr_renderer_destroy(v.renderer)); /* destroys the swapchain and the surface */
  CADR_CHECK(cadr_scene_destroy(v.scene));
  CADR_CHECK(cadr_context_destroy(v.context));
  glfwDestroyWindow(v.window);
  glfwTerminate();
  return status;
}
