/* headless: builds a small assembly entirely through the C API (no file) — a plate, a shared
 * bolt subgraph placed twelve times, a switch with two cover variants — renders it offscreen
 * and writes a PNG.
 *
 *   headless [output.png] [width] [height]     (default headless.png 800 600) */
#include "common/sample.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

int main(int argc, char **argv) {
  const char *output = argc > 1 ? argv[1] : "headless.png";
  uint32_t width = argc > 2 ? (uint32_t)atoi(argv[2]) : 800;
  uint32_t height = argc > 3 ? (uint32_t)atoi(argv[3]) : 600;
  CadrContext context;
  CadrScene scene;
  CadrRenderer renderer;
  CadrNode root, plate, bolt, cover_switch, node;
  CadrGeometry plate_box, shaft, head, cover_a, cover_b;
  CadrMaterial steel, paint, brass, glass;
  CadrMaterial plate_materials[3], shaft_materials[2], head_materials[2], cover_materials[3];
  struct CadrSceneStatistics statistics = {.size = sizeof(struct CadrSceneStatistics)};
  struct CadrBounds bounds;
  struct CadrCamera camera;
  struct CadrFrameStats stats = {.size = sizeof(struct CadrFrameStats)};
  CadrRendererSettings settings;
  const char *submission = NULL;
  bool cover_mask[2] = {false, true};
  double matrix[16];
  int i;

  sample_print_messages();
  CADR_CHECK(cadr_context_create(NULL, &context));
  CADR_CHECK(cadr_scene_create(&scene));
  CADR_CHECK(cadr_scene_root(scene, &root));

  steel = sample_material(scene, "steel", 0.62f, 0.64f, 0.66f, 1.0f, 0.35f);
  paint = sample_material(scene, "blue paint", 0.10f, 0.25f, 0.60f, 0.0f, 0.6f);
  brass = sample_material(scene, "brass", 0.78f, 0.60f, 0.25f, 1.0f, 0.3f);
  glass = sample_material(scene, "smoked cover", 0.25f, 0.28f, 0.30f, 0.0f, 0.1f);

  /* The plate: a painted box with a steel rim (one material per pair of faces). */
  plate_box = sample_box(scene, "plate", 1.2f, 1.2f, 0.1f);
  plate_materials[0] = steel;
  plate_materials[1] = steel;
  plate_materials[2] = paint;
  CADR_CHECK(cadr_scene_create_geo(scene, "plate", plate_box, plate_materials, 3, &plate));
  CADR_CHECK(cadr_scene_add_child(scene, root, plate));

  /* One bolt subgraph (shaft and head), shared by twelve transforms. */
  shaft = sample_cylinder(scene, "bolt shaft", 0.04f, 0.35f, 16);
  head = sample_cylinder(scene, "bolt head", 0.08f, 0.06f, 6);
  shaft_materials[0] = shaft_materials[1] = steel;
  head_materials[0] = head_materials[1] = brass;
  CADR_CHECK(cadr_scene_create_group(scene, "bolt", &bolt));
  CADR_CHECK(cadr_scene_create_geo(scene, "shaft", shaft, shaft_materials, 2, &node));
  CADR_CHECK(cadr_scene_add_child(scene, bolt, node));
  sample_translation(matrix, 0, 0, 0.35);
  {
    CadrNode head_place, head_geo;
    CADR_CHECK(cadr_scene_create_transform(scene, "head place", matrix, &head_place));
    CADR_CHECK(cadr_scene_create_geo(scene, "head", head, head_materials, 2, &head_geo));
    CADR_CHECK(cadr_scene_add_child(scene, head_place, head_geo));
    CADR_CHECK(cadr_scene_add_child(scene, bolt, head_place));
  }
  for (i = 0; i < 12; ++i) {
    double angle = 6.283185307179586 * i / 12.0;
    CadrNode place;
    sample_rotate_z_translate(matrix, angle, 0.95 * cos(angle), 0.95 * sin(angle), 0.0);
    CADR_CHECK(cadr_scene_create_transform(scene, "bolt place", matrix, &place));
    CADR_CHECK(cadr_scene_add_child(scene, place, bolt));
    CADR_CHECK(cadr_scene_add_child(scene, root, place));
  }

  /* Two cover variants under a switch; the second is shown. */
  cover_a = sample_box(scene, "cover (square)", 0.6f, 0.6f, 0.08f);
  cover_b = sample_cylinder(scene, "cover (round)", 0.7f, 0.12f, 48);
  cover_materials[0] = cover_materials[1] = cover_materials[2] = glass;
  CADR_CHECK(cadr_scene_create_switch(scene, "cover variants", &cover_switch));
  sample_translation(matrix, 0, 0, 0.1);
  {
    CadrNode lift, variant;
    CADR_CHECK(cadr_scene_create_transform(scene, "cover place", matrix, &lift));
    CADR_CHECK(cadr_scene_add_child(scene, root, lift));
    CADR_CHECK(cadr_scene_add_child(scene, lift, cover_switch));
    CADR_CHECK(cadr_scene_create_geo(scene, "square cover", cover_a, cover_materials, 3, &variant));
    CADR_CHECK(cadr_scene_add_child(scene, cover_switch, variant));
    CADR_CHECK(cadr_scene_create_geo(scene, "round cover", cover_b, cover_materials, 2, &variant));
    CADR_CHECK(cadr_scene_add_child(scene, cover_switch, variant));
  }
  CADR_CHECK(cadr_scene_set_switch_mask(scene, cover_switch, cover_mask, 2));

  CADR_CHECK(cadr_scene_statistics(scene, &statistics));
  CADR_CHECK(cadr_scene_bounds(scene, &bounds));
  printf("assembly: %llu nodes, %llu geometries, %llu materials, %llu parts shown, %llu triangles\n",
         (unsigned long long)statistics.nodes, (unsigned long long)statistics.geometries,
         (unsigned long long)statistics.materials,
         (unsigned long long)statistics.visible_instances,
         (unsigned long long)statistics.visible_triangles);

  CADR_CHECK(cadr_renderer_create(context, width, height, &renderer));
  {
    const double direction[3] = {0.9, -1.3, 1.1};
    CADR_CHECK(cadr_camera_fit(&bounds, (double)width / height, direction, &camera));
  }
  /* Settings are one struct: read the renderer's, change what you need, apply them. */
  settings.size = sizeof settings;
  CADR_CHECK(cadr_renderer_settings(renderer, &settings));
  settings.shade_mode = CADR_SHADE_EDGES;
  CADR_CHECK(cadr_renderer_apply_settings(renderer, &settings));
  CADR_CHECK(cadr_renderer_render(renderer, scene, &camera, &stats));
  CADR_CHECK(cadr_renderer_save_png(renderer, output));
  CADR_CHECK(cadr_renderer_technique(renderer, CADR_TECHNIQUE_KIND_SUBMISSION, &submission));
  printf("rendered %ux%u with %s: %llu draws in %llu calls, %.1f us CPU -> %s\n", width, height,
         submission, (unsigned long long)stats.draws, (unsigned long long)stats.draw_calls,
         stats.cpu_us, output);

  CADR_CHECK(cadr_renderer_destroy(renderer));
  CADR_CHECK(cadr_scene_destroy(scene));
  CADR_CHECK(cadr_context_destroy(context));
  return 0;
}
