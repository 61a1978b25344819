/* A host as it was compiled against cadr 1.0's header (the copy of `include/cadr.h` beside it,
 * frozen): it must keep working against every later libcadr.so.1. It touches the structs a
 * newer library may grow (the options, device info, geometry and material descriptions,
 * statistics, renderer settings, frame stats, pick results, timings, memory usage) and prints
 * what it got, one `key value` line each; the test
 * (tests/tests/c_api_abi.rs) checks the values. Never edit this file or its header: freeze a
 * new pair for a new version instead. */
#include "cadr.h"

#include <stdio.h>
#include <string.h>

#define CHECK(call)                                                                          \
  do {                                                                                       \
    enum CadrResult result_ = (call);                                                        \
    if (result_ != CADR_RESULT_OK) {                                                         \
      char message_[512] = "";                                                               \
      size_t length_ = 0;                                                                    \
      cadr_last_error_message(message_, sizeof message_, &length_);                          \
      fprintf(stderr, "%s failed: %s (%s)\n", #call, cadr_result_string(result_), message_); \
      return 1;                                                                              \
    }                                                                                        \
  } while (0)

enum { WIDTH = 96, HEIGHT = 64 };

int main(void) {
  /* A box of 12 triangles, one part. */
  static const float positions[8 * 3] = {-1, -1, -1, 1, -1, -1, 1, 1, -1, -1, 1, -1,
                                         -1, -1, 1,  1, -1, 1,  1, 1, 1,  -1, 1, 1};
  static const uint32_t indices[36] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                       2, 3, 7, 2, 7, 6, 1, 2, 6, 1, 6, 5, 0, 4, 7, 0, 7, 3};
  static uint8_t pixels[WIDTH * HEIGHT * 4];
  const double direction[3] = {1.0, -1.5, 0.8};
  struct CadrContextOptions options;
  struct CadrDeviceInfo device;
  struct CadrGeometryDesc geometry_desc;
  struct CadrMaterialDesc material_desc;
  struct CadrPart part;
  struct CadrSceneStatistics statistics;
  struct CadrBounds bounds;
  struct CadrCamera camera;
  struct CadrRendererSettings settings;
  struct CadrFrameStats stats;
  struct CadrPickResult picked;
  struct CadrTimings timings;
  struct CadrMemoryUsage memory;
  CadrContext context;
  CadrScene scene;
  CadrRenderer renderer;
  CadrGeometry geometry;
  CadrMaterial material;
  CadrNode root, node;
  uint64_t validation_errors = 0;
  const uint8_t *center = pixels + ((HEIGHT / 2) * WIDTH + WIDTH / 2) * 4;

  memset(&options, 0, sizeof options);
  options.size = sizeof options;
  CHECK(cadr_context_options_default(&options));
  options.validation = true;
  CHECK(cadr_context_create(&options, &context));
  memset(&device, 0xAB, sizeof device);
  device.size = sizeof device;
  CHECK(cadr_context_device_info(context, &device));
  printf("device_api_major %u\n", (unsigned)(device.api_version >> 22));
  printf("device_validation %d\n", device.validation ? 1 : 0);

  CHECK(cadr_scene_create(&scene));
  CHECK(cadr_scene_root(scene, &root));
  memset(&part, 0, sizeof part);
  part.index_count = 36;
  memset(&geometry_desc, 0, sizeof geometry_desc);
  geometry_desc.size = sizeof geometry_desc;
  geometry_desc.name = "box";
  geometry_desc.positions = positions;
  geometry_desc.vertex_count = 8;
  geometry_desc.indices = indices;
  geometry_desc.index_count = 36;
  geometry_desc.parts = &part;
  geometry_desc.part_count = 1;
  CHECK(cadr_scene_create_geometry(scene, &geometry_desc, &geometry));
  memset(&material_desc, 0, sizeof material_desc);
  material_desc.size = sizeof material_desc;
  material_desc.name = "red";
  material_desc.base_color[0] = 0.9f;
  material_desc.base_color[1] = 0.1f;
  material_desc.base_color[2] = 0.1f;
  material_desc.base_color[3] = 1.0f;
  material_desc.roughness = 0.5f;
  CHECK(cadr_scene_create_material(scene, &material_desc, &material));
  CHECK(cadr_scene_create_geo(scene, "box", geometry, &material, 1, &node));
  CHECK(cadr_scene_add_child(scene, root, node));
  memset(&statistics, 0xAB, sizeof statistics);
  statistics.size = sizeof statistics;
  CHECK(cadr_scene_statistics(scene, &statistics));
  printf("scene_triangles %llu\n", (unsigned long long)statistics.visible_triangles);

  CHECK(cadr_renderer_create(context, WIDTH, HEIGHT, &renderer));
  CHECK(cadr_scene_bounds(scene, &bounds));
  CHECK(cadr_camera_fit(&bounds, (double)WIDTH / HEIGHT, direction, &camera));
  memset(&settings, 0xAB, sizeof settings);
  settings.size = sizeof settings;
  CHECK(cadr_renderer_settings(renderer, &settings));
  printf("settings_shade_solid %d\n", settings.shade_mode == CADR_SHADE_SOLID ? 1 : 0);
  settings.msaa_samples = 1;
  settings.ssao = false;
  CHECK(cadr_renderer_apply_settings(renderer, &settings));
  memset(&stats, 0xAB, sizeof stats);
  stats.size = sizeof stats;
  CHECK(cadr_renderer_render(renderer, scene, &camera, &stats));
  printf("frame_presented %d\n", stats.presented ? 1 : 0);
  printf("frame_draws %llu\n", (unsigned long long)stats.draws);
  CHECK(cadr_renderer_read_pixels(renderer, pixels, sizeof pixels));
  printf("center_red_over_green %d\n", center[0] > center[1] + 40 ? 1 : 0);

  memset(&picked, 0, sizeof picked);
  picked.size = sizeof picked;
  CHECK(cadr_renderer_pick(renderer, scene, &camera, WIDTH / 2, HEIGHT / 2, &picked));
  printf("pick_hits %llu\n", (unsigned long long)picked.hit_count);
  printf("pick_node_matches %d\n", picked.hit_count > 0 && picked.hits[0].node == node ? 1 : 0);
  cadr_pick_result_free(&picked);

  memset(&timings, 0, sizeof timings);
  timings.size = sizeof timings;
  CHECK(cadr_timings(&timings));
  printf("timings_device_positive %d\n", timings.device_ms > 0.0 ? 1 : 0);
  memset(&memory, 0, sizeof memory);
  memory.size = sizeof memory;
  CHECK(cadr_context_memory_usage(context, &memory));
  printf("memory_allocated_positive %d\n", memory.device_allocated_bytes > 0 ? 1 : 0);

  CHECK(cadr_context_validation_error_count(context, &validation_errors));
  printf("validation_errors %llu\n", (unsigned long long)validation_errors);
  CHECK(cadr_renderer_destroy(renderer));
  CHECK(cadr_scene_destroy(scene));
  CHECK(cadr_context_destroy(context));
  return 0;
}
