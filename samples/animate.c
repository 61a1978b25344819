/* animate: loads a scene and moves its parts every frame through the API — an exploded view
 * growing and shrinking — printing the CPU cost of the edits and of the frame: the incremental
 * scene tree seen from a host.
 *
 *   animate [scene] [frames] [output.png]     (default gen:demo, 120 frames, no image)
 *
 * The scene is a .gltf/.glb/.csf/.csf.gz file or a generator such as gen:graphicscard. */
#define _POSIX_C_SOURCE 199309L
#include "common/sample.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double now_us(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec * 1e6 + (double)t.tv_nsec / 1e3;
}

struct Piece {
  CadrNode offset; /* a Transform inserted above the piece, moved every frame */
  double direction[3];
};

int main(int argc, char **argv) {
  const char *source = argc > 1 ? argv[1] : "gen:demo";
  int frames = argc > 2 ? atoi(argv[2]) : 120;
  const char *output = argc > 3 ? argv[3] : NULL;
  const uint32_t width = 800, height = 600;
  CadrContext context;
  CadrScene scene;
  CadrRenderer renderer;
  CadrNode root, parent;
  struct CadrLoadResult loaded = {.size = sizeof(struct CadrLoadResult)};
  struct CadrBounds bounds, piece_bounds;
  struct CadrCamera camera;
  struct CadrFrameStats stats = {.size = sizeof(struct CadrFrameStats)};
  struct Piece *pieces;
  uint32_t count = 0, i;
  double center[3], radius, identity[16], matrix[16];
  double edit_sum = 0, update_sum = 0, frame_sum = 0;
  int frame, depth;

  CADR_CHECK(cadr_context_create(NULL, &context));
  CADR_CHECK(cadr_scene_create(&scene));
  CADR_CHECK(cadr_scene_root(scene, &root));
  CADR_CHECK(cadr_scene_load(scene, source, root, &loaded));
  CADR_CHECK(cadr_scene_bounds(scene, &bounds));
  for (i = 0; i < 3; ++i) {
    center[i] = 0.5 * (bounds.min[i] + bounds.max[i]);
  }
  radius = 0.5 * sqrt(pow(bounds.max[0] - bounds.min[0], 2) + pow(bounds.max[1] - bounds.min[1], 2) +
                      pow(bounds.max[2] - bounds.min[2], 2));

  /* The pieces: the children of the first node (from the file's root) that has several. */
  parent = loaded.root;
  for (depth = 0; depth < 6; ++depth) {
    CADR_CHECK(cadr_scene_child_count(scene, parent, &count));
    if (count != 1) {
      break;
    }
    CADR_CHECK(cadr_scene_child(scene, parent, 0, &parent));
  }
  pieces = (struct Piece *)calloc(count > 0 ? count : 1, sizeof *pieces);
  if (pieces == NULL) {
    fprintf(stderr, "out of memory\n");
    return 1;
  }
  sample_identity(identity);
  /* Each piece moves away from the assembly's centre, along the line through its own centre. */
  for (i = 0; i < count; ++i) {
    CadrNode child;
    double length = 0;
    int axis;
    CADR_CHECK(cadr_scene_child(scene, parent, 0, &child));
    CADR_CHECK(cadr_scene_node_bounds(scene, child, &piece_bounds));
    for (axis = 0; axis < 3; ++axis) {
      double c = piece_bounds.min[axis] <= piece_bounds.max[axis]
                     ? 0.5 * (piece_bounds.min[axis] + piece_bounds.max[axis])
                     : center[axis];
      pieces[i].direction[axis] = c - center[axis];
      length += pieces[i].direction[axis] * pieces[i].direction[axis];
    }
    length = sqrt(length);
    for (axis = 0; axis < 3; ++axis) {
      pieces[i].direction[axis] = length > 1e-9 * radius ? pieces[i].direction[axis] / length : 0.0;
    }
    /* Re-hang the child under its own offset Transform (appended, so the order is kept). */
    CADR_CHECK(cadr_scene_create_transform(scene, "explode offset", identity, &pieces[i].offset));
    CADR_CHECK(cadr_scene_remove_child(scene, parent, child));
    CADR_CHECK(cadr_scene_add_child(scene, pieces[i].offset, child));
    CADR_CHECK(cadr_scene_add_child(scene, parent, pieces[i].offset));
  }
  printf("%s: %u pieces explode from the centre over %d frames\n", source, count, frames);

  CADR_CHECK(cadr_renderer_create(context, width, height, &renderer));
  {
    /* Frame the fully exploded assembly. */
    struct CadrBounds wide = bounds;
    for (i = 0; i < 3; ++i) {
      wide.min[i] -= radius * 0.6;
      wide.max[i] += radius * 0.6;
    }
    CADR_CHECK(cadr_camera_fit(&wide, (double)width / height, NULL, &camera));
  }
  for (frame = 0; frame < frames; ++frame) {
    double phase = 0.5 - 0.5 * cos(6.283185307179586 * frame / 60.0);
    double distance = 0.6 * radius * phase, start = now_us(), edits;
    for (i = 0; i < count; ++i) {
      sample_translation(matrix, pieces[i].direction[0] * distance,
                         pieces[i].direction[1] * distance, pieces[i].direction[2] * distance);
      CADR_CHECK(cadr_scene_set_matrix(scene, pieces[i].offset, matrix));
    }
    edits = now_us() - start;
    CADR_CHECK(cadr_renderer_render(renderer, scene, &camera, &stats));
    edit_sum += edits;
    update_sum += stats.scene_update_us;
    frame_sum += stats.cpu_us;
    if ((frame + 1) % 30 == 0 || frame + 1 == frames) {
      printf("frame %d: %u matrix edits %.1f us, scene update %.1f us, frame CPU %.1f us, "
             "GPU %.1f us, %llu draws in %llu calls, %llu bytes uploaded\n",
             frame + 1, count, edits, stats.scene_update_us, stats.cpu_us, stats.gpu_us,
             (unsigned long long)stats.draws, (unsigned long long)stats.draw_calls,
             (unsigned long long)stats.bytes_uploaded);
    }
  }
  if (frames > 0) {
    printf("mean per frame: edits %.1f us, scene update %.1f us, frame CPU %.1f us\n",
           edit_sum / frames, update_sum / frames, frame_sum / frames);
  }
  if (output != NULL) {
    CADR_CHECK(cadr_renderer_save_png(renderer, output));
    printf("last frame -> %s\n", output);
  }
  free(pieces);
  cadr_load_result_free(&loaded);
  CADR_CHECK(cadr_renderer_destroy(renderer));
  CADR_CHECK(cadr_scene_destroy(scene));
  CADR_CHECK(cadr_context_destroy(context));
  return 0;
}
