/* The C API from several threads at once, as its documentation allows: two renderers of one
 * context draw and pick the same scene on two threads while a third edits that scene (moves,
 * hides, adds and removes nodes) and a fourth loads scenes into another one and queries both.
 * Then a renderer is destroyed while another thread is drawing with it: that thread's call
 * finishes and its next one is refused with CADR_RESULT_DESTROYED_HANDLE, never a crash.
 *
 * Built by tests/tests/c_api.rs with the strict flags (C11), and again with ThreadSanitizer. Exits
 * non-zero on the first failed call. */
#define _POSIX_C_SOURCE 200809L
#include "cadr.h"
#include "checks.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { FRAMES = 40, EDITS = 400, LOADS = 8, MOVERS = 6, W = 64, H = 48 };

static const double identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

struct Shared {
  CadrContext context;
  CadrScene scene;      /* drawn by both renderers, edited by the editor */
  CadrScene other;      /* loaded into by the loader */
  CadrNode movers[MOVERS];
  CadrRenderer renderers[2];
  struct CadrBounds bounds;
  atomic_int frames_drawn;
};

struct Drawer {
  struct Shared *shared;
  int index;
};

static void orbit_camera(const struct CadrBounds *bounds, int frame, struct CadrCamera *camera) {
  double centre[3], eye[3], radius = 0.0;
  int axis;
  for (axis = 0; axis < 3; ++axis) {
    double half = 0.5 * (bounds->max[axis] - bounds->min[axis]);
    centre[axis] = 0.5 * (bounds->max[axis] + bounds->min[axis]);
    radius += half * half;
  }
  radius = sqrt(radius) + 1.0;
  eye[0] = centre[0] + 3.0 * radius * cos(frame * 0.1);
  eye[1] = centre[1] + radius;
  eye[2] = centre[2] + 3.0 * radius * sin(frame * 0.1);
  OK(cadr_camera_look_at(eye, centre, 40.0, (double)W / H, 0.01 * radius, 10.0 * radius,
                         camera));
}

/* Draws and picks the shared scene. */
static void *draw(void *argument) {
  struct Drawer *drawer = (struct Drawer *)argument;
  struct Shared *s = drawer->shared;
  CadrRenderer renderer = s->renderers[drawer->index];
  struct CadrCamera camera;
  struct CadrFrameStats stats = {.size = sizeof(struct CadrFrameStats)};
  CadrPickResult picked = {sizeof(struct CadrPickResult), NULL, 0};
  int frame;
  for (frame = 0; frame < FRAMES; ++frame) {
    orbit_camera(&s->bounds, frame + 17 * drawer->index, &camera);
    OK(cadr_renderer_render(renderer, s->scene, &camera, &stats));
    CHECK(stats.presented);
    if (frame % 8 == 0) {
      OK(cadr_renderer_pick_rect(renderer, s->scene, &camera, 0, 0, W, H, &picked));
      cadr_pick_result_free(&picked);
    }
    atomic_fetch_add(&s->frames_drawn, 1);
  }
  return NULL;
}

/* Moves, hides and shows the movers; adds and removes nodes below the root. */
static void *edit(void *argument) {
  struct Shared *s = (struct Shared *)argument;
  CadrNode root = 0, added = 0;
  double matrix[16];
  int step;
  OK(cadr_scene_root(s->scene, &root));
  for (step = 0; step < EDITS; ++step) {
    CadrNode mover = s->movers[step % MOVERS];
    memcpy(matrix, identity, sizeof matrix);
    matrix[12] = (step % MOVERS) * 1.5;
    matrix[13] = 0.5 * sin(step * 0.05);
    OK(cadr_scene_set_matrix(s->scene, mover, matrix));
    if (step % 25 == 0) {
      OK(cadr_scene_set_flags(s->scene, mover, step % 50 == 0 ? 0 : CADR_NODE_VISIBLE |
                                                                      CADR_NODE_PICKABLE));
    }
    if (step % 40 == 0) {
      OK(cadr_scene_create_transform(s->scene, "added", identity, &added));
      OK(cadr_scene_add_child(s->scene, root, added));
      OK(cadr_scene_add_child(s->scene, added, s->movers[0])); /* a shared subgraph */
    }
    if (step % 40 == 20) {
      OK(cadr_scene_remove_child(s->scene, root, added));
      OK(cadr_scene_destroy_node(s->scene, added));
    }
  }
  /* Every mover shown again. */
  for (step = 0; step < MOVERS; ++step) {
    OK(cadr_scene_set_flags(s->scene, s->movers[step], CADR_NODE_VISIBLE | CADR_NODE_PICKABLE));
  }
  return NULL;
}

/* Loads scenes into the other scene and reads both scenes' statistics. */
static void *load(void *argument) {
  struct Shared *s = (struct Shared *)argument;
  CadrNode root = 0;
  struct CadrLoadResult loaded = {.size = sizeof(struct CadrLoadResult)};
  struct CadrSceneStatistics statistics = {.size = sizeof(struct CadrSceneStatistics)};
  struct CadrBounds bounds;
  uint64_t instances = 0;
  int step;
  OK(cadr_scene_root(s->other, &root));
  for (step = 0; step < LOADS; ++step) {
    OK(cadr_scene_load(s->other, step % 2 ? "gen:grid:parts=40" : "gen:demo", root, &loaded));
    CHECK(loaded.node_count > 0);
    cadr_load_result_free(&loaded);
    OK(cadr_scene_statistics(s->other, &statistics));
    CHECK(statistics.instances > instances);
    instances = statistics.instances;
    OK(cadr_scene_statistics(s->scene, &statistics));
    OK(cadr_scene_bounds(s->scene, &bounds));
  }
  return NULL;
}

static CadrGeometry cube(CadrScene scene) {
  static const float positions[] = {-0.5f, -0.5f, -0.5f, 0.5f, -0.5f, -0.5f, 0.5f, 0.5f, -0.5f,
                                    -0.5f, 0.5f,  -0.5f, -0.5f, -0.5f, 0.5f, 0.5f, -0.5f, 0.5f,
                                    0.5f,  0.5f,  0.5f,  -0.5f, 0.5f,  0.5f};
  static const uint32_t indices[] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                     2, 3, 7, 2, 7, 6, 1, 2, 6, 1, 6, 5, 0, 4, 7, 0, 7, 3};
  static const struct CadrPart parts[] = {{0, 36, 0, 0}};
  struct CadrGeometryDesc desc = {.size = sizeof(struct CadrGeometryDesc)};
  CadrGeometry geometry = 0;
  memset(&desc, 0, sizeof desc);
  desc.size = sizeof desc;
  desc.positions = positions;
  desc.vertex_count = 8;
  desc.indices = indices;
  desc.index_count = 36;
  desc.parts = parts;
  desc.part_count = 1;
  desc.name = "cube";
  OK(cadr_scene_create_geometry(scene, &desc, &geometry));
  return geometry;
}

/* Draws with a renderer until another thread destroys it. */
static void *draw_until_destroyed(void *argument) {
  struct Shared *s = (struct Shared *)argument;
  struct CadrCamera camera;
  enum CadrResult result = CADR_RESULT_OK;
  int frame = 0;
  while (result == CADR_RESULT_OK && frame < 100000) {
    orbit_camera(&s->bounds, frame++, &camera);
    result = cadr_renderer_render(s->renderers[1], s->scene, &camera, NULL);
    atomic_fetch_add(&s->frames_drawn, 1);
  }
  CHECK(result == CADR_RESULT_DESTROYED_HANDLE);
  return NULL;
}

int main(void) {
  struct Shared s;
  struct CadrContextOptions options = {.size = sizeof(struct CadrContextOptions)};
  struct Drawer drawers[2];
  pthread_t threads[4];
  CadrNode root = 0, geo = 0;
  CadrGeometry geometry;
  CadrMaterial material = 0;
  uint64_t errors = 99;
  int i;
  struct CadrMaterialDesc red = {.size = sizeof(struct CadrMaterialDesc)};

  memset(&s, 0, sizeof s);
  atomic_init(&s.frames_drawn, 0);
  OK(cadr_context_options_default(&options));
  options.validation = true;
  OK(cadr_context_create(&options, &s.context));
  OK(cadr_scene_create(&s.scene));
  OK(cadr_scene_create(&s.other));
  OK(cadr_scene_root(s.scene, &root));
  geometry = cube(s.scene);
  memset(&red, 0, sizeof red);
  red.size = sizeof red;
  red.base_color[0] = 0.8f;
  red.base_color[1] = 0.2f;
  red.base_color[2] = 0.1f;
  red.base_color[3] = 1.0f;
  red.roughness = 0.5f;
  OK(cadr_scene_create_material(s.scene, &red, &material));
  for (i = 0; i < MOVERS; ++i) {
    double matrix[16];
    memcpy(matrix, identity, sizeof matrix);
    matrix[12] = i * 1.5;
    OK(cadr_scene_create_transform(s.scene, "mover", matrix, &s.movers[i]));
    OK(cadr_scene_create_geo(s.scene, "cube", geometry, &material, 1, &geo));
    OK(cadr_scene_add_child(s.scene, s.movers[i], geo));
    OK(cadr_scene_add_child(s.scene, root, s.movers[i]));
  }
  OK(cadr_scene_bounds(s.scene, &s.bounds));
  for (i = 0; i < 2; ++i) {
    OK(cadr_renderer_create(s.context, W, H, &s.renderers[i]));
    drawers[i].shared = &s;
    drawers[i].index = i;
  }
  OK(set_frames_in_flight(s.renderers[1], 2));

  CHECK(pthread_create(&threads[0], NULL, draw, &drawers[0]) == 0);
  CHECK(pthread_create(&threads[1], NULL, draw, &drawers[1]) == 0);
  CHECK(pthread_create(&threads[2], NULL, edit, &s) == 0);
  CHECK(pthread_create(&threads[3], NULL, load, &s) == 0);
  for (i = 0; i < 4; ++i) {
    CHECK(pthread_join(threads[i], NULL) == 0);
  }
  CHECK(atomic_load(&s.frames_drawn) == 2 * FRAMES);

  /* Destroying a renderer another thread draws with: its call finishes, the next is refused. */
  CHECK(pthread_create(&threads[0], NULL, draw_until_destroyed, &s) == 0);
  while (atomic_load(&s.frames_drawn) < 2 * FRAMES + 3) {
  }
  OK(cadr_renderer_destroy(s.renderers[1]));
  CHECK(pthread_join(threads[0], NULL) == 0);

  OK(cadr_context_validation_error_count(s.context, &errors));
  CHECK(errors == 0);
  OK(cadr_renderer_destroy(s.renderers[0]));
  OK(cadr_scene_destroy(s.other));
  OK(cadr_scene_destroy(s.scene));
  OK(cadr_context_destroy(s.context));
  printf("threads: %d frames drawn on 2 threads while editing and loading; checks passed\n",
         2 * FRAMES);
  return 0;
}
