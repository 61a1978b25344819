/* Every function of the C API called the way a C host calls it: the successful path and each
 * error path (NULL arguments, destroyed and foreign handles, bad files, invalid technique
 * combinations, wrong sizes). Exits non-zero on the first failed check.
 *
 * Built by tests/tests/c_api.rs with -std=c99 -Wall -Wextra -Wpedantic -Werror, and again under
 * AddressSanitizer (leaks included). */
#define _POSIX_C_SOURCE 200809L
#include "cadr.h"

#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <fcntl.h>
#include <unistd.h>

static int checks = 0;

static const char *last_error(void) {
  static char text[4096];
  size_t length = 0;
  if (cadr_last_error_message(text, sizeof text, &length) != CADR_RESULT_OK) {
    return "(message too long)";
  }
  return text;
}

#define EXPECT(call, expected)                                                                \
  do {                                                                                        \
    enum CadrResult result_ = (call);                                                         \
    ++checks;                                                                                 \
    if (result_ != (expected)) {                                                              \
      fprintf(stderr, "%s:%d: %s gave %s (%d), expected %s: %s\n", __FILE__, __LINE__, #call, \
              cadr_result_string((int32_t)result_), (int)result_, #expected, last_error());  \
      exit(1);                                                                                \
    }                                                                                         \
  } while (0)

#define OK(call) EXPECT(call, CADR_RESULT_OK)

#define CHECK(condition)                                                           \
  do {                                                                             \
    ++checks;                                                                      \
    if (!(condition)) {                                                            \
      fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #condition); \
      exit(1);                                                                     \
    }                                                                              \
  } while (0)

/* The last error message contains `part`. */
#define MESSAGE_HAS(part)                                                                \
  do {                                                                                   \
    ++checks;                                                                            \
    if (strstr(last_error(), (part)) == NULL) {                                          \
      fprintf(stderr, "%s:%d: message \"%s\" lacks \"%s\"\n", __FILE__, __LINE__,        \
              last_error(), (part));                                                     \
      exit(1);                                                                           \
    }                                                                                    \
  } while (0)

static const double identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};

static void translation(double matrix[16], double x, double y, double z) {
  memcpy(matrix, identity, sizeof identity);
  matrix[12] = x;
  matrix[13] = y;
  matrix[14] = z;
}

/* A unit cube with two parts (top+bottom faces, and the four sides). */
static const float cube_positions[] = {
    -0.5f, -0.5f, -0.5f, 0.5f, -0.5f, -0.5f, 0.5f, 0.5f, -0.5f, -0.5f, 0.5f, -0.5f,
    -0.5f, -0.5f, 0.5f,  0.5f, -0.5f, 0.5f,  0.5f, 0.5f, 0.5f,  -0.5f, 0.5f, 0.5f};
static const uint32_t cube_indices[] = {
    /* bottom, top */
    0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7,
    /* sides */
    0, 1, 5, 0, 5, 4, 1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7};
static const struct CadrPart cube_parts[] = {{0, 12, 0, 0}, {12, 24, 0, 0}};

/* A geometry of one part, its normals computed by cadr. */
static struct CadrGeometryDesc geometry_desc(const char *name, const float *positions,
                                             uint32_t vertex_count, const uint32_t *indices,
                                             uint32_t index_count) {
  struct CadrGeometryDesc desc;
  memset(&desc, 0, sizeof desc);
  desc.size = sizeof desc;
  desc.name = name;
  desc.positions = positions;
  desc.vertex_count = vertex_count;
  desc.indices = indices;
  desc.index_count = index_count;
  return desc;
}

static struct CadrGeometryDesc cube_desc(void) {
  struct CadrGeometryDesc desc = geometry_desc("cube", cube_positions, 8, cube_indices, 36);
  desc.parts = cube_parts;
  desc.part_count = 2;
  return desc;
}

static void test_basics(void) {
  uint32_t major = 99, minor = 99, patch = 99;
  char expected[64];
  cadr_version(&major, &minor, &patch);
  CHECK(major == CADR_VERSION_MAJOR && minor == CADR_VERSION_MINOR && patch == CADR_VERSION_PATCH);
  cadr_version(NULL, NULL, NULL);
  snprintf(expected, sizeof expected, "%u.%u.%u", major, minor, patch);
  CHECK(strcmp(cadr_version_string(), expected) == 0);

  CHECK(strcmp(cadr_result_string(CADR_RESULT_OK), "ok") == 0);
  CHECK(strcmp(cadr_result_string(CADR_RESULT_DESTROYED_HANDLE), "destroyed handle") == 0);
  CHECK(strcmp(cadr_result_string(CADR_RESULT_PLUGIN_FAILED), "technique plugin failed") == 0);
  CHECK(strcmp(cadr_result_string(1234), "unknown result") == 0);

  /* The last error: size query, too small a buffer, NULL length. */
  {
    size_t needed = 0;
    char small[4];
    EXPECT(cadr_scene_create(NULL), CADR_RESULT_NULL_ARGUMENT);
    EXPECT(cadr_last_error_message(NULL, 0, &needed), CADR_RESULT_BUFFER_TOO_SMALL);
    CHECK(needed == strlen("scene is NULL") + 1);
    EXPECT(cadr_last_error_message(small, sizeof small, &needed), CADR_RESULT_BUFFER_TOO_SMALL);
    EXPECT(cadr_last_error_message(small, sizeof small, NULL), CADR_RESULT_NULL_ARGUMENT);
    CHECK(strcmp(last_error(), "scene is NULL") == 0);
  }
}

static void test_camera(void) {
  struct CadrCamera camera;
  const double eye[3] = {0, 0, 5}, target[3] = {0, 0, 0}, nan_eye[3] = {0, NAN, 5};
  struct CadrBounds bounds = {{-1, -1, -1}, {1, 1, 1}};
  const double direction[3] = {0, 0, 1}, zero[3] = {0, 0, 0};
  OK(cadr_camera_look_at(eye, target, 45, 1.5, 0.1, 100, &camera));
  CHECK(fabs(camera.view[14] + 5.0) < 1e-12); /* the origin is 5 units in front of the eye */
  EXPECT(cadr_camera_look_at(NULL, target, 45, 1.5, 0.1, 100, &camera), CADR_RESULT_NULL_ARGUMENT);
  EXPECT(cadr_camera_look_at(eye, target, 45, 1.5, 0.1, 100, NULL), CADR_RESULT_NULL_ARGUMENT);
  EXPECT(cadr_camera_look_at(nan_eye, target, 45, 1.5, 0.1, 100, &camera),
         CADR_RESULT_INVALID_ARGUMENT);
  MESSAGE_HAS("eye[1]");
  EXPECT(cadr_camera_look_at(eye, eye, 45, 1.5, 0.1, 100, &camera), CADR_RESULT_INVALID_ARGUMENT);
  EXPECT(cadr_camera_look_at(eye, target, 180, 1.5, 0.1, 100, &camera),
         CADR_RESULT_INVALID_ARGUMENT);
  EXPECT(cadr_camera_look_at(eye, target, 45, 0, 0.1, 100, &camera), CADR_RESULT_INVALID_ARGUMENT);
  EXPECT(cadr_camera_look_at(eye, target, 45, 1, 1, 0.5, &camera), CADR_RESULT_INVALID_ARGUMENT);
  OK(cadr_camera_fit(&bounds, 1.0, direction, &camera));
  CHECK(camera.view[14] < -1.0); /* the box's centre is in front of the eye */
  OK(cadr_camera_fit(&bounds, 1.0, NULL, &camera));
  EXPECT(cadr_camera_fit(NULL, 1.0, NULL, &camera), CADR_RESULT_NULL_ARGUMENT);
  EXPECT(cadr_camera_fit(&bounds, 1.0, zero, &camera), CADR_RESULT_INVALID_ARGUMENT);
  EXPECT(cadr_camera_fit(&bounds, -1.0, NULL, &camera), CADR_RESULT_INVALID_ARGUMENT);
}

static CadrContext test_context(void) {
  struct CadrContextOptions options = {.size = sizeof(struct CadrContextOptions)};
  CadrContext context = NULL;
  struct CadrDeviceInfo info = {.size = sizeof(struct CadrDeviceInfo)};
  void *instance = NULL;
  uint32_t count = 0, i;
  struct CadrTechniqueInfo technique = {.size = sizeof(struct CadrTechniqueInfo)};
  struct CadrPluginRefusal refusal = {.size = sizeof(struct CadrPluginRefusal)};
  const char *bad_extension[1] = {"VK_cadr_no_such_extension"};

  EXPECT(cadr_context_options_default(NULL), CADR_RESULT_NULL_ARGUMENT);
  OK(cadr_context_options_default(&options));
  CHECK(options.size == sizeof options && options.device_index == -1 && options.default_plugin_dirs);
  EXPECT(cadr_context_create(&options, NULL), CADR_RESULT_NULL_ARGUMENT);
  options.size = 2;
  EXPECT(cadr_context_create(&options, &context), CADR_RESULT_INVALID_ARGUMENT);
  MESSAGE_HAS("options->size is 2");
  CHECK(context == NULL); /* nothing written on failure */
  options.size = sizeof options;
  OK(cadr_context_options_default(&options));
  options.device_extensions = bad_extension;
  options.device_extension_count = 1;
  EXPECT(cadr_context_create(&options, &context), CADR_RESULT_UNSUPPORTED);
  MESSAGE_HAS("VK_cadr_no_such_extension");
  options.device_extensions = NULL;
  EXPECT(cadr_context_create(&options, &context), CADR_RESULT_NULL_ARGUMENT);
  MESSAGE_HAS("options.device_extensions");
  OK(cadr_context_options_default(&options));
  options.device_index = 999;
  EXPECT(cadr_context_create(&options, &context), CADR_RESULT_VULKAN);
  OK(cadr_context_options_default(&options));
  options.validation = true;
  OK(cadr_context_create(&options, &context));
  CHECK(context != NULL);

  OK(cadr_context_device_info(context, &info));
  CHECK(strlen(info.name) > 0 && info.validation &&
        (info.features & CADR_DEVICE_FEATURE_PRESENTATION) == 0);
  CHECK(info.api_version >= ((1u << 22) | (3u << 12)));
  CHECK(info.video_memory_bytes > 0); /* lavapipe offers the host's memory */
  EXPECT(cadr_context_device_info(context, NULL), CADR_RESULT_NULL_ARGUMENT);
  OK(cadr_context_vulkan_instance(context, &instance));
  CHECK(instance != NULL);
  EXPECT(cadr_context_vulkan_instance(context, NULL), CADR_RESULT_NULL_ARGUMENT);

  OK(cadr_context_technique_count(context, &count));
  CHECK(count >= 20);
  for (i = 0; i < count; ++i) {
    OK(cadr_context_technique(context, i, &technique));
    CHECK(technique.kind <= CADR_TECHNIQUE_KIND_TRANSPARENCY);
    CHECK(strlen(technique.name) > 0 && strlen(technique.description) > 0);
    /* The built-in techniques come first, then those of the plugin libraries. */
    CHECK(i < 5 ? strcmp(technique.library, "built-in") == 0
                : strstr(technique.library, "cadr_plugin_") != NULL);
    CHECK(technique.supported == (technique.unsupported_reason[0] == '\0'));
  }
  EXPECT(cadr_context_technique(context, count, &technique), CADR_RESULT_NOT_FOUND);
  EXPECT(cadr_context_technique(context, 0, NULL), CADR_RESULT_NULL_ARGUMENT);
  OK(cadr_context_refusal_count(context, &count));
  for (i = 0; i < count; ++i) {
    OK(cadr_context_refusal(context, i, &refusal));
    CHECK(strlen(refusal.library) > 0 && strlen(refusal.reason) > 0);
  }
  EXPECT(cadr_context_refusal(context, count, &refusal), CADR_RESULT_NOT_FOUND);
  EXPECT(cadr_context_refusal_count(context, NULL), CADR_RESULT_NULL_ARGUMENT);
  EXPECT(cadr_context_technique_count(NULL, &count), CADR_RESULT_NULL_ARGUMENT);
  return context;
}

struct Built {
  CadrScene scene;
  CadrNode root, mover, geo, switch_node;
  CadrGeometry cube;
  CadrMaterial red, blue;
};

static struct Built test_scene(void) {
  struct Built b;
  struct CadrGeometryDesc desc = cube_desc();
  struct CadrMaterialDesc red = {sizeof(struct CadrMaterialDesc), "red", {0.8f, 0.1f, 0.1f, 1.0f}, 0.0f, 0.5f};
  struct CadrMaterialDesc blue = {sizeof(struct CadrMaterialDesc), "blue", {0.1f, 0.2f, 0.9f, 1.0f}, 0.5f, 0.3f};
  CadrMaterial parts[2];
  CadrNode group, lod, lod_screen, billboard, child, second;
  double matrix[16];
  const double distances[2] = {10.0, 100.0}, angles[1] = {0.1}, bad_distances[2] = {5.0, 1.0};
  bool mask[2] = {true, false};
  uint32_t count = 0, flags = 0;
  uint32_t bad_indices[3] = {0, 1, 8};
  struct CadrSceneStatistics statistics = {.size = sizeof(struct CadrSceneStatistics)};
  struct CadrBounds bounds;

  OK(cadr_scene_create(&b.scene));
  OK(cadr_scene_root(b.scene, &b.root));
  EXPECT(cadr_scene_root(b.scene, NULL), CADR_RESULT_NULL_ARGUMENT);
  CHECK(b.root != 0);

  /* Geometry and materials from the host's arrays. */
  OK(cadr_scene_create_geometry(b.scene, &desc, &b.cube));
  OK(cadr_scene_geometry_bounds(b.scene, b.cube, &bounds));
  CHECK(bounds.min[0] == -0.5 && bounds.max[2] == 0.5);
  EXPECT(cadr_scene_create_geometry(b.scene, NULL, &b.cube), CADR_RESULT_NULL_ARGUMENT);
  desc.indices = bad_indices;
  desc.index_count = 3;
  desc.parts = NULL;
  desc.part_count = 0;
  EXPECT(cadr_scene_create_geometry(b.scene, &desc, &b.cube), CADR_RESULT_INVALID_ARGUMENT);
  MESSAGE_HAS("desc.indices[2]");
  desc = cube_desc();
  desc.index_count = 35;
  desc.parts = NULL;
  desc.part_count = 0;
  EXPECT(cadr_scene_create_geometry(b.scene, &desc, &b.cube), CADR_RESULT_INVALID_ARGUMENT);
  desc = cube_desc();
  desc.positions = NULL;
  EXPECT(cadr_scene_create_geometry(b.scene, &desc, &b.cube), CADR_RESULT_NULL_ARGUMENT);
  MESSAGE_HAS("desc.positions");
  desc = cube_desc();
  OK(cadr_scene_create_material(b.scene, &red, &b.red));
  OK(cadr_scene_create_material(b.scene, &blue, &b.blue));
  red.base_color[1] = 2.0f;
  EXPECT(cadr_scene_create_material(b.scene, &red, &parts[0]), CADR_RESULT_INVALID_ARGUMENT);
  MESSAGE_HAS("base_color[1]");
  EXPECT(cadr_scene_set_material(b.scene, b.red, &red), CADR_RESULT_INVALID_ARGUMENT);
  red.base_color[1] = 0.1f;
  OK(cadr_scene_set_material(b.scene, b.red, &red));
  /* Input structs of other versions: a newer host's zeroed extra field is accepted, a set one
   * refused by name; a size that cannot be a struct's is refused. */
  {
    struct {
      struct CadrMaterialDesc desc;
      uint64_t field_of_a_later_version;
    } newer;
    memset(&newer, 0, sizeof newer);
    newer.desc = red;
    newer.desc.size = sizeof newer;
    OK(cadr_scene_set_material(b.scene, b.red, &newer.desc));
    newer.field_of_a_later_version = 7;
    EXPECT(cadr_scene_set_material(b.scene, b.red, &newer.desc), CADR_RESULT_INVALID_ARGUMENT);
    MESSAGE_HAS("CadrMaterialDesc, which this library");
    newer.desc.size = 3;
    EXPECT(cadr_scene_set_material(b.scene, b.red, &newer.desc), CADR_RESULT_INVALID_ARGUMENT);
    MESSAGE_HAS("desc->size is 3");
  }

  /* Nodes of every kind. */
  parts[0] = b.red;
  parts[1] = b.blue;
  OK(cadr_scene_create_geo(b.scene, "cube", b.cube, parts, 2, &b.geo));
  EXPECT(cadr_scene_create_geo(b.scene, "cube", b.cube, parts, 1, &child),
         CADR_RESULT_INVALID_ARGUMENT);
  MESSAGE_HAS("part materials");
  EXPECT(cadr_scene_create_geo(b.scene, "cube", b.cube, NULL, 2, &child), CADR_RESULT_NULL_ARGUMENT);
  OK(cadr_scene_create_group(b.scene, NULL, &group));
  translation(matrix, 0.25, 0, 0);
  OK(cadr_scene_create_transform(b.scene, "mover", matrix, &b.mover));
  matrix[5] = NAN;
  EXPECT(cadr_scene_create_transform(b.scene, "bad", matrix, &child), CADR_RESULT_INVALID_ARGUMENT);
  MESSAGE_HAS("matrix[5]");
  EXPECT(cadr_scene_create_transform(b.scene, "bad", NULL, &child), CADR_RESULT_NULL_ARGUMENT);
  OK(cadr_scene_create_switch(b.scene, "switch", &b.switch_node));
  OK(cadr_scene_create_lod(b.scene, "lod", distances, 2, &lod));
  EXPECT(cadr_scene_create_lod(b.scene, "lod", bad_distances, 2, &child),
         CADR_RESULT_INVALID_ARGUMENT);
  OK(cadr_scene_create_lod_by_screen_size(b.scene, "lod by size", 1.0, angles, 1, &lod_screen));
  OK(cadr_scene_create_billboard(b.scene, "billboard", &billboard));
  EXPECT(cadr_scene_create_billboard(b.scene, "billboard", NULL), CADR_RESULT_NULL_ARGUMENT);

  /* root -> group -> mover -> switch -> [geo, second]; lod, billboard under group. */
  OK(cadr_scene_add_child(b.scene, b.root, group));
  OK(cadr_scene_add_child(b.scene, group, b.mover));
  OK(cadr_scene_add_child(b.scene, b.mover, b.switch_node));
  OK(cadr_scene_add_child(b.scene, b.switch_node, b.geo));
  OK(cadr_scene_create_geo(b.scene, "second", b.cube, parts, 2, &second));
  OK(cadr_scene_insert_child(b.scene, b.switch_node, 1, second));
  EXPECT(cadr_scene_insert_child(b.scene, b.switch_node, 7, second), CADR_RESULT_INVALID_ARGUMENT);
  OK(cadr_scene_add_child(b.scene, group, lod));
  OK(cadr_scene_add_child(b.scene, group, lod_screen));
  OK(cadr_scene_add_child(b.scene, group, billboard));
  EXPECT(cadr_scene_add_child(b.scene, b.mover, group), CADR_RESULT_INVALID_ARGUMENT);
  MESSAGE_HAS("cycle");
  OK(cadr_scene_child_count(b.scene, b.switch_node, &count));
  CHECK(count == 2);
  OK(cadr_scene_child(b.scene, b.switch_node, 1, &child));
  CHECK(child == second);
  EXPECT(cadr_scene_child(b.scene, b.switch_node, 2, &child), CADR_RESULT_NOT_FOUND);
  EXPECT(cadr_scene_child_count(b.scene, b.switch_node, NULL), CADR_RESULT_NULL_ARGUMENT);
  {
    /* Names and kinds, for a host's model tree: the size first, then the name. */
    char name[16];
    size_t length = 0;
    enum CadrNodeKind kind = CADR_NODE_KIND_GROUP;
    EXPECT(cadr_scene_node_name(b.scene, b.switch_node, NULL, 0, &length),
           CADR_RESULT_BUFFER_TOO_SMALL);
    CHECK(length == strlen("switch") + 1);
    EXPECT(cadr_scene_node_name(b.scene, b.switch_node, name, 3, &length),
           CADR_RESULT_BUFFER_TOO_SMALL);
    MESSAGE_HAS("needs 7 bytes");
    OK(cadr_scene_node_name(b.scene, b.switch_node, name, sizeof name, &length));
    CHECK(strcmp(name, "switch") == 0 && length == 6);
    EXPECT(cadr_scene_node_name(b.scene, b.switch_node, name, sizeof name, NULL),
           CADR_RESULT_NULL_ARGUMENT);
    OK(cadr_scene_node_kind(b.scene, b.switch_node, &kind));
    CHECK(kind == CADR_NODE_KIND_SWITCH);
    OK(cadr_scene_node_kind(b.scene, b.mover, &kind));
    CHECK(kind == CADR_NODE_KIND_TRANSFORM);
    OK(cadr_scene_node_kind(b.scene, b.geo, &kind));
    CHECK(kind == CADR_NODE_KIND_GEO);
    OK(cadr_scene_node_kind(b.scene, lod, &kind));
    CHECK(kind == CADR_NODE_KIND_LOD);
    OK(cadr_scene_node_kind(b.scene, billboard, &kind));
    CHECK(kind == CADR_NODE_KIND_BILLBOARD);
    EXPECT(cadr_scene_node_kind(b.scene, b.geo, NULL), CADR_RESULT_NULL_ARGUMENT);
    EXPECT(cadr_scene_node_kind(b.scene, 0x1234, &kind), CADR_RESULT_FOREIGN_HANDLE);
    EXPECT(cadr_scene_node_name(b.scene, 0x1234, name, sizeof name, &length),
           CADR_RESULT_FOREIGN_HANDLE);
  }

  /* Edits. */
  OK(cadr_scene_set_switch_mask(b.scene, b.switch_node, mask, 2));
  EXPECT(cadr_scene_set_switch_mask(b.scene, b.switch_node, mask, 1), CADR_RESULT_INVALID_ARGUMENT);
  EXPECT(cadr_scene_set_switch_mask(b.scene, b.geo, mask, 2), CADR_RESULT_INVALID_ARGUMENT);
  OK(cadr_scene_set_flags(b.scene, group, CADR_NODE_VISIBLE | CADR_NODE_HIGHLIGHTED));
  OK(cadr_scene_flags(b.scene, group, &flags));
  CHECK(flags == (CADR_NODE_VISIBLE | CADR_NODE_HIGHLIGHTED));
  OK(cadr_scene_set_flags(b.scene, group, CADR_NODE_VISIBLE | CADR_NODE_PICKABLE));
  EXPECT(cadr_scene_set_flags(b.scene, group, 64), CADR_RESULT_INVALID_ARGUMENT);
  EXPECT(cadr_scene_flags(b.scene, group, NULL), CADR_RESULT_NULL_ARGUMENT);
  OK(cadr_scene_set_part_material(b.scene, b.geo, 1, b.red));
  OK(cadr_scene_set_part_material(b.scene, b.geo, 1, b.blue));
  EXPECT(cadr_scene_set_part_material(b.scene, b.geo, 2, b.red), CADR_RESULT_INVALID_ARGUMENT);
  EXPECT(cadr_scene_set_part_material(b.scene, b.mover, 0, b.red), CADR_RESULT_INVALID_ARGUMENT);
  OK(cadr_scene_set_part_visible(b.scene, b.geo, 0, false));
  OK(cadr_scene_set_part_visible(b.scene, b.geo, 0, true));
  EXPECT(cadr_scene_set_part_visible(b.scene, b.geo, 5, false), CADR_RESULT_INVALID_ARGUMENT);
  translation(matrix, 0, 0, 0);
  OK(cadr_scene_set_matrix(b.scene, b.mover, matrix));
  EXPECT(cadr_scene_set_matrix(b.scene, b.geo, matrix), CADR_RESULT_INVALID_ARGUMENT);
  EXPECT(cadr_scene_set_matrix(b.scene, b.mover, NULL), CADR_RESULT_NULL_ARGUMENT);
  OK(cadr_scene_replace_geometry(b.scene, b.cube, &desc));
  desc.part_count = 1;
  EXPECT(cadr_scene_replace_geometry(b.scene, b.cube, &desc), CADR_RESULT_INVALID_ARGUMENT);
  desc = cube_desc();

  /* Only the geo shows (the switch hides `second`): 2 instances, 12 triangles. */
  OK(cadr_scene_statistics(b.scene, &statistics));
  CHECK(statistics.geometries == 1 && statistics.materials == 2);
  CHECK(statistics.instances == 4 && statistics.visible_instances == 2);
  CHECK(statistics.visible_triangles == 12);
  OK(cadr_scene_bounds(b.scene, &bounds));
  CHECK(bounds.min[0] == -0.5 && bounds.max[0] == 0.5);
  OK(cadr_scene_node_bounds(b.scene, b.geo, &bounds));
  CHECK(bounds.min[1] == -0.5 && bounds.max[1] == 0.5);
  OK(cadr_scene_node_bounds(b.scene, second, &bounds));
  CHECK(bounds.min[0] > bounds.max[0]); /* hidden by the switch: empty */
  EXPECT(cadr_scene_node_bounds(b.scene, b.geo, NULL), CADR_RESULT_NULL_ARGUMENT);
  EXPECT(cadr_scene_bounds(b.scene, NULL), CADR_RESULT_NULL_ARGUMENT);

  /* In use: refused; unused after removal: destroyed. */
  EXPECT(cadr_scene_destroy_geometry(b.scene, b.cube), CADR_RESULT_IN_USE);
  EXPECT(cadr_scene_destroy_material(b.scene, b.red), CADR_RESULT_IN_USE);
  OK(cadr_scene_remove_child(b.scene, b.switch_node, second));
  EXPECT(cadr_scene_remove_child(b.scene, b.switch_node, second), CADR_RESULT_INVALID_ARGUMENT);
  OK(cadr_scene_destroy_node(b.scene, second));
  EXPECT(cadr_scene_destroy_node(b.scene, b.root), CADR_RESULT_INVALID_ARGUMENT);

  /* Destroyed and foreign handles. */
  EXPECT(cadr_scene_add_child(b.scene, group, second), CADR_RESULT_DESTROYED_HANDLE);
  EXPECT(cadr_scene_destroy_node(b.scene, second), CADR_RESULT_DESTROYED_HANDLE);
  {
    enum CadrNodeKind kind;
    size_t length = 0;
    EXPECT(cadr_scene_node_kind(b.scene, second, &kind), CADR_RESULT_DESTROYED_HANDLE);
    EXPECT(cadr_scene_node_name(b.scene, second, NULL, 0, &length), CADR_RESULT_DESTROYED_HANDLE);
  }
  EXPECT(cadr_scene_add_child(b.scene, group, 0x1234), CADR_RESULT_FOREIGN_HANDLE);
  EXPECT(cadr_scene_add_child(b.scene, group, 0), CADR_RESULT_NULL_ARGUMENT);
  EXPECT(cadr_scene_destroy_geometry(b.scene, b.red), CADR_RESULT_FOREIGN_HANDLE);
  EXPECT(cadr_scene_set_part_material(b.scene, b.geo, 0, b.cube), CADR_RESULT_FOREIGN_HANDLE);
  EXPECT(cadr_scene_create_geo(b.scene, "x", b.red, parts, 2, &child), CADR_RESULT_FOREIGN_HANDLE);
  EXPECT(cadr_scene_root((CadrScene)(uintptr_t)0x5151, &child), CADR_RESULT_FOREIGN_HANDLE);
  return b;
}

static void test_loading(CadrScene scene, CadrNode root) {
  struct CadrLoadResult loaded = {.size = sizeof(struct CadrLoadResult)};
  struct CadrSceneStatistics statistics = {.size = sizeof(struct CadrSceneStatistics)};
  const char *missing = "/nonexistent/cadr/engine.gltf";
  memset(&loaded, 0, sizeof loaded);
  loaded.size = sizeof loaded;
  EXPECT(cadr_scene_load(scene, missing, root, &loaded), CADR_RESULT_LOAD_FAILED);
  MESSAGE_HAS(missing);
  EXPECT(cadr_scene_load(scene, "model.obj", root, &loaded), CADR_RESULT_LOAD_FAILED);
  MESSAGE_HAS("unknown scene format");
  EXPECT(cadr_scene_load(scene, "gen:no-such-generator", root, &loaded), CADR_RESULT_LOAD_FAILED);
  EXPECT(cadr_scene_load(scene, NULL, root, &loaded), CADR_RESULT_NULL_ARGUMENT);
  EXPECT(cadr_scene_load(scene, "gen:demo", root, NULL), CADR_RESULT_NULL_ARGUMENT);
  EXPECT(cadr_scene_load(scene, "gen:demo", 0x4e00000000000042ull, &loaded),
         CADR_RESULT_FOREIGN_HANDLE);
  CHECK(loaded.nodes == NULL); /* nothing written on failure */

  OK(cadr_scene_load(scene, "gen:grid:parts=40", root, &loaded));
  CHECK(loaded.root != 0 && loaded.node_count > 1 && loaded.nodes[0] == loaded.root);
  CHECK(loaded.geometry_count >= 1 && loaded.material_count >= 1);
  OK(cadr_scene_statistics(scene, &statistics));
  CHECK(statistics.visible_instances >= 40);
  /* What was loaded can be edited through its handles. */
  OK(cadr_scene_set_flags(scene, loaded.root, 0));
  OK(cadr_scene_statistics(scene, &statistics));
  CHECK(statistics.visible_instances == 2);
  OK(cadr_scene_destroy_node(scene, loaded.root));
  cadr_load_result_free(&loaded);
  CHECK(loaded.nodes == NULL && loaded.node_count == 0);
  cadr_load_result_free(&loaded);
  cadr_load_result_free(NULL);
}

/* What the message callback received. */
struct Messages {
  int warnings;
  int others;
  char last_warning[512];
};

static void record_message(uint32_t severity, const char *message, void *user_data) {
  struct Messages *messages = (struct Messages *)user_data;
  if (severity == CADR_MESSAGE_WARNING) {
    ++messages->warnings;
    snprintf(messages->last_warning, sizeof messages->last_warning, "%s", message);
  } else {
    ++messages->others;
  }
}

/* A glTF triangle with a second primitive of points, which cadr does not draw yet and says so. */
static const char *points_gltf =
    "{\"asset\":{\"version\":\"2.0\"},\"scene\":0,\"scenes\":[{\"nodes\":[0]}],"
    "\"nodes\":[{\"mesh\":0,\"name\":\"tri\"}],\"meshes\":[{\"primitives\":["
    "{\"attributes\":{\"POSITION\":0}},{\"attributes\":{\"POSITION\":0},\"mode\":0}]}],"
    "\"buffers\":[{\"byteLength\":36,\"uri\":\"data:application/octet-stream;base64,"
    "AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA\"}],"
    "\"bufferViews\":[{\"buffer\":0,\"byteLength\":36}],"
    "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":3,\"type\":\"VEC3\","
    "\"min\":[0,0,0],\"max\":[1,1,0]}]}";

/* Loads `path` under `root` and drops what it made. */
static void load_and_drop(CadrScene scene, CadrNode root, const char *path) {
  struct CadrLoadResult loaded = {.size = sizeof(struct CadrLoadResult)};
  memset(&loaded, 0, sizeof loaded);
  loaded.size = sizeof loaded;
  OK(cadr_scene_load(scene, path, root, &loaded));
  CHECK(loaded.geometry_count == 1);
  OK(cadr_scene_destroy_node(scene, loaded.root));
  cadr_load_result_free(&loaded);
}

/* The message callback hears what a load leaves out, at the severities asked for, until it is
 * removed. */
static void test_messages(CadrScene scene, CadrNode root) {
  struct Messages messages;
  char path[512];
  const char *out_dir = getenv("CADR_TEST_OUT");
  FILE *file;
  memset(&messages, 0, sizeof messages);
  snprintf(path, sizeof path, "%s/points.gltf", out_dir ? out_dir : "/tmp");
  file = fopen(path, "w");
  CHECK(file != NULL);
  CHECK(fputs(points_gltf, file) >= 0);
  CHECK(fclose(file) == 0);

  EXPECT(cadr_set_message_callback(record_message, &messages, 0), CADR_RESULT_INVALID_ARGUMENT);
  MESSAGE_HAS("severity 0");
  EXPECT(cadr_set_message_callback(record_message, &messages, 5), CADR_RESULT_INVALID_ARGUMENT);
  load_and_drop(scene, root, path); /* no callback yet: nothing heard */
  CHECK(messages.warnings == 0);

  OK(cadr_set_message_callback(record_message, &messages, CADR_MESSAGE_WARNING));
  load_and_drop(scene, root, path);
  CHECK(messages.warnings == 1);
  CHECK(strstr(messages.last_warning, "primitive 1: Points primitives are not drawn yet") != NULL);
  CHECK(strstr(messages.last_warning, path) == messages.last_warning); /* it names the file */
  CHECK(messages.others == 0);

  /* Errors only: the warning is not sent. */
  OK(cadr_set_message_callback(record_message, &messages, CADR_MESSAGE_ERROR));
  load_and_drop(scene, root, path);
  CHECK(messages.warnings == 1);

  /* Removed: nothing is sent. */
  OK(cadr_set_message_callback(record_message, &messages, CADR_MESSAGE_DEBUG));
  OK(cadr_set_message_callback(NULL, NULL, CADR_MESSAGE_DEBUG));
  load_and_drop(scene, root, path);
  CHECK(messages.warnings == 1);
  remove(path);
}

/* The renderer's settings, as a host reads them. */
static CadrRendererSettings settings_of(CadrRenderer renderer) {
  CadrRendererSettings settings;
  memset(&settings, 0, sizeof settings);
  settings.size = sizeof settings;
  OK(cadr_renderer_settings(renderer, &settings));
  return settings;
}

/* What the renderer's device and window offer. */
static CadrRendererCapabilities capabilities_of(CadrRenderer renderer) {
  CadrRendererCapabilities capabilities;
  memset(&capabilities, 0, sizeof capabilities);
  capabilities.size = sizeof capabilities;
  OK(cadr_renderer_capabilities(renderer, &capabilities));
  return capabilities;
}

/* Whether two settings agree field by field (the struct has padding, which memcmp would
 * compare). */
static bool settings_equal(const CadrRendererSettings *a, const CadrRendererSettings *b) {
  return a->size == b->size && a->shade_mode == b->shade_mode &&
         a->highlight_style == b->highlight_style &&
         memcmp(a->highlight_color, b->highlight_color, sizeof a->highlight_color) == 0 &&
         a->outline_width == b->outline_width &&
         memcmp(a->edge_color, b->edge_color, sizeof a->edge_color) == 0 &&
         a->silhouettes == b->silhouettes && a->dashed_hidden_lines == b->dashed_hidden_lines &&
         a->ssao == b->ssao && a->textures == b->textures &&
         memcmp(a->background_top, b->background_top, sizeof a->background_top) == 0 &&
         memcmp(a->background_bottom, b->background_bottom, sizeof a->background_bottom) == 0 &&
         a->msaa_samples == b->msaa_samples && a->section_flags == b->section_flags &&
         memcmp(a->section_cap_colors, b->section_cap_colors, sizeof a->section_cap_colors) == 0 &&
         a->min_pixels == b->min_pixels && a->lod_error == b->lod_error &&
         a->frame_replay == b->frame_replay &&
         a->pick_through_translucent == b->pick_through_translucent &&
         a->frames_in_flight == b->frames_in_flight && a->present_mode == b->present_mode &&
         a->depth_to_host == b->depth_to_host;
}

/* The settings last applied by SET and SET_RGB. */
static CadrRendererSettings applied;

/* Changes one setting as a host does (read, change, apply); gives the result of applying. */
#define SET(renderer, field, value)                                    \
  (applied = settings_of(renderer), applied.field = (value),           \
   cadr_renderer_apply_settings((renderer), &applied))
#define SET_RGB(renderer, field, rgb)                                  \
  (applied = settings_of(renderer), memcpy(applied.field, (rgb), sizeof applied.field), \
   cadr_renderer_apply_settings((renderer), &applied))

/* Reads the colour at `offset` of the settings. */
static void get_rgb(CadrRenderer renderer, size_t offset, float rgb[3]) {
  CadrRendererSettings settings = settings_of(renderer);
  memcpy(rgb, (const char *)&settings + offset, 3 * sizeof(float));
}

static enum CadrResult set_background(CadrRenderer renderer, const float top[3],
                                      const float bottom[3]) {
  applied = settings_of(renderer);
  memcpy(applied.background_top, top, sizeof applied.background_top);
  memcpy(applied.background_bottom, bottom, sizeof applied.background_bottom);
  return cadr_renderer_apply_settings(renderer, &applied);
}

static void get_background(CadrRenderer renderer, float top[3], float bottom[3]) {
  CadrRendererSettings settings = settings_of(renderer);
  memcpy(top, settings.background_top, sizeof settings.background_top);
  memcpy(bottom, settings.background_bottom, sizeof settings.background_bottom);
}

static unsigned pixel_difference(const uint8_t *a, const uint8_t *b, size_t size) {
  unsigned differing = 0;
  size_t i;
  for (i = 0; i < size; i += 4) {
    if (abs(a[i] - b[i]) + abs(a[i + 1] - b[i + 1]) + abs(a[i + 2] - b[i + 2]) > 30) {
      ++differing;
    }
  }
  return differing;
}

/* The RGB of pixel (x, y) of a W-wide RGBA picture. */
#define PIXEL(picture, width, x, y) (&(picture)[4 * ((size_t)(width) * (y) + (x))])

static bool reddish(const uint8_t *p) { return p[0] > 2 * p[1] && p[0] > 2 * p[2]; }
static bool greenish(const uint8_t *p) { return p[1] > 2 * p[0] && p[1] > 2 * p[2]; }
static bool bluish(const uint8_t *p) { return p[2] > 2 * p[0] && p[2] > 2 * p[1]; }

/* Renders `scene` and reads the picture back into `picture` (the renderer's size). */
static void render_into(CadrRenderer renderer, CadrScene scene, const struct CadrCamera *camera,
                        uint8_t *picture) {
  uint32_t width = 0, height = 0;
  OK(cadr_renderer_size(renderer, &width, &height));
  OK(cadr_renderer_render(renderer, scene, camera, NULL));
  OK(cadr_renderer_read_pixels(renderer, picture, (size_t)width * height * 4));
}

/* Textures, a material's texture and alpha mode, and vertex colours from the host's arrays: a
   square facing the camera, textured red on its left half and blue on its right (2x1 texels,
   magnified as blocks); flipped by a UV transform; cut away where the texture's alpha is 0
   under a mask; coloured green by its vertices without the texture. Every error path too. */
static void test_host_textures(CadrRenderer renderer, uint32_t width, uint32_t height) {
  static const float positions[] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
  static const uint32_t indices[] = {0, 1, 2, 0, 2, 3};
  /* (0, 0) is the image's top left. */
  static const float uvs[] = {0, 1, 1, 1, 1, 0, 0, 0};
  static const float greens[] = {0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0, 1};
  static const float too_bright[] = {0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0, 1, 0, 2, 0, 1};
  static const float not_finite_uvs[] = {0, 1, 1, 1, 1, NAN, 0, 0};
  static const uint8_t red_blue[] = {255, 0, 0, 255, 0, 0, 255, 255};
  static const uint8_t red_clear[] = {255, 0, 0, 255, 0, 0, 255, 0};
  static const float mirrored[6] = {-1, 0, 1, 0, 1, 0};
  static const float not_finite_transform[6] = {1, 0, INFINITY, 0, 1, 0};
  static const double front[3] = {0, 0, 1};
  struct CadrGeometryDesc desc = {.size = sizeof(struct CadrGeometryDesc)};
  struct CadrMaterialDesc white = {sizeof(struct CadrMaterialDesc), "white", {1.0f, 1.0f, 1.0f, 1.0f}, 0.0f, 0.8f};
  struct CadrTextureDesc texture_desc = {.size = sizeof(struct CadrTextureDesc)};
  struct CadrBounds bounds;
  struct CadrCamera camera;
  CadrScene scene = NULL;
  CadrNode root = 0, geo = 0;
  CadrGeometry square = 0;
  CadrMaterial material = 0;
  CadrTexture texture = 0, clear = 0, spare = 0;
  uint8_t *picture = (uint8_t *)malloc((size_t)width * height * 4);
  const uint32_t left = width / 2 - width / 8, right = width / 2 + width / 8, row = height / 2;
  CHECK(picture != NULL);

  OK(cadr_scene_create(&scene));
  OK(cadr_scene_root(scene, &root));
  desc = geometry_desc("square", positions, 4, indices, 6);
  OK(cadr_scene_create_geometry(scene, &desc, &square));
  OK(cadr_scene_create_material(scene, &white, &material));
  OK(cadr_scene_create_geo(scene, "square", square, &material, 1, &geo));
  OK(cadr_scene_add_child(scene, root, geo));

  memset(&texture_desc, 0, sizeof texture_desc);

  texture_desc.size = sizeof texture_desc;
  texture_desc.name = "red|blue";
  texture_desc.width = 2;
  texture_desc.height = 1;
  texture_desc.texels = red_blue;
  texture_desc.wrap_s = CADR_WRAP_CLAMP_TO_EDGE;
  texture_desc.wrap_t = CADR_WRAP_REPEAT;
  texture_desc.magnify_nearest = true;
  OK(cadr_scene_create_texture(scene, &texture_desc, &texture));
  CHECK(texture != 0);
  texture_desc.texels = red_clear;
  texture_desc.name = "red|clear";
  OK(cadr_scene_create_texture(scene, &texture_desc, &clear));
  OK(cadr_scene_set_geometry_attributes(scene, square, 4, uvs, NULL));
  OK(cadr_scene_set_material_texture(scene, material, texture, NULL));

  OK(cadr_scene_bounds(scene, &bounds));
  OK(cadr_camera_fit(&bounds, (double)width / height, front, &camera));
  render_into(renderer, scene, &camera, picture);
  CHECK(reddish(PIXEL(picture, width, left, row)) && bluish(PIXEL(picture, width, right, row)));

  /* u' = 1 - u: the halves swap. */
  OK(cadr_scene_set_material_texture(scene, material, texture, mirrored));
  render_into(renderer, scene, &camera, picture);
  CHECK(bluish(PIXEL(picture, width, left, row)) && reddish(PIXEL(picture, width, right, row)));

  /* A mask cuts the right half away: the background shows there, as at the row's left end. */
  OK(cadr_scene_set_material_texture(scene, material, clear, NULL));
  OK(cadr_scene_set_material_alpha_mode(scene, material, CADR_ALPHA_MASK, 0.5f));
  render_into(renderer, scene, &camera, picture);
  CHECK(reddish(PIXEL(picture, width, left, row)));
  CHECK(memcmp(PIXEL(picture, width, right, row), PIXEL(picture, width, 0, row), 3) == 0);
  {
    CadrPickResult picked = {sizeof(struct CadrPickResult), NULL, 0};
    OK(cadr_renderer_pick(renderer, scene, &camera, left, row, &picked));
    CHECK(picked.hit_count == 1);
    cadr_pick_result_free(&picked);
    OK(cadr_renderer_pick(renderer, scene, &camera, right, row, &picked));
    CHECK(picked.hit_count == 0); /* picking goes through the holes */
  }
  /* Opaque: the clear texels draw (blue-free, so not the background). */
  OK(cadr_scene_set_material_alpha_mode(scene, material, CADR_ALPHA_OPAQUE, 0.0f));
  render_into(renderer, scene, &camera, picture);
  CHECK(memcmp(PIXEL(picture, width, right, row), PIXEL(picture, width, 0, row), 3) != 0);

  /* Without the texture, green vertex colours colour the white material. */
  OK(cadr_scene_set_material_texture(scene, material, 0, NULL));
  OK(cadr_scene_set_material_alpha_mode(scene, material, CADR_ALPHA_BLEND, 0.0f));
  OK(cadr_scene_set_geometry_attributes(scene, square, 4, NULL, greens));
  render_into(renderer, scene, &camera, picture);
  CHECK(greenish(PIXEL(picture, width, left, row)) && greenish(PIXEL(picture, width, right, row)));
  /* Taken away, the material's white shows. */
  OK(cadr_scene_set_geometry_attributes(scene, square, 4, NULL, NULL));
  render_into(renderer, scene, &camera, picture);
  CHECK(!greenish(PIXEL(picture, width, left, row)));

  /* Errors name what is wrong; nothing changes. */
  EXPECT(cadr_scene_create_texture(scene, NULL, &spare), CADR_RESULT_NULL_ARGUMENT);
  EXPECT(cadr_scene_create_texture(scene, &texture_desc, NULL), CADR_RESULT_NULL_ARGUMENT);
  texture_desc.width = 0;
  EXPECT(cadr_scene_create_texture(scene, &texture_desc, &spare), CADR_RESULT_INVALID_ARGUMENT);
  MESSAGE_HAS("0×1 texels");
  texture_desc.width = 2;
  texture_desc.wrap_t = 7;
  EXPECT(cadr_scene_create_texture(scene, &texture_desc, &spare), CADR_RESULT_INVALID_ARGUMENT);
  MESSAGE_HAS("desc.wrap_t is 7");
  texture_desc.wrap_t = CADR_WRAP_MIRRORED_REPEAT;
  texture_desc.texels = NULL;
  EXPECT(cadr_scene_create_texture(scene, &texture_desc, &spare), CADR_RESULT_NULL_ARGUMENT);
  MESSAGE_HAS("desc.texels");
  texture_desc.width = 100000;
  texture_desc.height = 100000;
  EXPECT(cadr_scene_create_texture(scene, &texture_desc, &spare), CADR_RESULT_INVALID_ARGUMENT);
  MESSAGE_HAS("memory budget");
  CHECK(spare == 0);
  EXPECT(cadr_scene_set_geometry_attributes(scene, square, 3, uvs, NULL),
         CADR_RESULT_INVALID_ARGUMENT);
  MESSAGE_HAS("has 4 vertices");
  EXPECT(cadr_scene_set_geometry_attributes(scene, square, 4, NULL, too_bright),
         CADR_RESULT_INVALID_ARGUMENT);
  MESSAGE_HAS("colors[13] (vertex 3)");
  EXPECT(cadr_scene_set_geometry_attributes(scene, square, 4, not_finite_uvs, NULL),
         CADR_RESULT_INVALID_ARGUMENT);
  MESSAGE_HAS("uvs[5] (vertex 2)");
  EXPECT(cadr_scene_set_material_texture(scene, material, texture, not_finite_transform),
         CADR_RESULT_INVALID_ARGUMENT);
  MESSAGE_HAS("uv_transform[2]");
  EXPECT(cadr_scene_set_material_texture(scene, material, material, NULL),
         CADR_RESULT_FOREIGN_HANDLE);
  EXPECT(cadr_scene_set_material_texture(scene, texture, texture, NULL),
         CADR_RESULT_FOREIGN_HANDLE);
  EXPECT(cadr_scene_set_material_alpha_mode(scene, material, 3, 0.5f),
         CADR_RESULT_INVALID_ARGUMENT);
  EXPECT(cadr_scene_set_material_alpha_mode(scene, material, CADR_ALPHA_MASK, 1.5f),
         CADR_RESULT_INVALID_ARGUMENT);
  MESSAGE_HAS("cutoff is 1.5");
  /* A texture in use stays; unused, it goes, and its handle is then a destroyed one. */
  OK(cadr_scene_set_material_texture(scene, material, texture, NULL));
  EXPECT(cadr_scene_destroy_texture(scene, texture), CADR_RESULT_IN_USE);
  OK(cadr_scene_destroy_texture(scene, clear));
  EXPECT(cadr_scene_destroy_texture(scene, clear), CADR_RESULT_DESTROYED_HANDLE);
  EXPECT(cadr_scene_set_material_texture(scene, material, clear, NULL),
         CADR_RESULT_DESTROYED_HANDLE);
  EXPECT(cadr_scene_destroy_texture(scene, 0), CADR_RESULT_NULL_ARGUMENT);
  OK(cadr_scene_set_material_texture(scene, material, 0, NULL));
  OK(cadr_scene_destroy_texture(scene, texture));
  OK(cadr_scene_destroy(scene));
  free(picture);
}

static void test_renderer(CadrContext context, struct Built *b) {
  enum { W = 96, H = 64 };
  CadrRenderer renderer = NULL, other = NULL;
  struct CadrCamera camera;
  struct CadrFrameStats stats = {.size = sizeof(struct CadrFrameStats)};
  struct CadrBounds bounds;
  uint8_t *first = (uint8_t *)malloc(W * H * 4), *second = (uint8_t *)malloc(W * H * 4);
  uint32_t width = 0, height = 0, mode = 99, kind;
  int step;
  const char *name = NULL;
  double matrix[16];
  struct CadrTechniqueSelection selection = {sizeof(struct CadrTechniqueSelection), NULL, NULL, NULL, NULL};
  const char *kinds[4][2] = {{"arena", "per-geometry"},
                             {"ssbo-index", "push"},
                             {"groups-mdi-replay", "individual"},
                             {"frustum", "none"}};
  CHECK(first != NULL && second != NULL);

  EXPECT(cadr_renderer_create(context, 0, 64, &renderer), CADR_RESULT_INVALID_ARGUMENT);
  EXPECT(cadr_renderer_create(context, 96, 20000, &renderer), CADR_RESULT_INVALID_ARGUMENT);
  EXPECT(cadr_renderer_create(context, W, H, NULL), CADR_RESULT_NULL_ARGUMENT);
  EXPECT(cadr_renderer_create((CadrContext)b->scene, W, H, &renderer), CADR_RESULT_FOREIGN_HANDLE);
  EXPECT(cadr_renderer_create_for_surface(context, 0, W, H, &renderer), CADR_RESULT_NULL_ARGUMENT);
  EXPECT(cadr_renderer_create_for_surface(context, 0x1234, W, H, &renderer),
         CADR_RESULT_UNSUPPORTED);
  MESSAGE_HAS("VK_KHR_surface");
  OK(cadr_renderer_create(context, W, H, &renderer));
  OK(cadr_renderer_size(renderer, &width, &height));
  CHECK(width == W && height == H);
  {
    /* No frame yet: no pass times, and no buffer needed for none. */
    size_t none = 99;
    OK(cadr_renderer_gpu_pass_times(renderer, NULL, 0, &none));
    CHECK(none == 0);
  }
  EXPECT(cadr_renderer_size(renderer, NULL, &height), CADR_RESULT_NULL_ARGUMENT);

  /* The fastest combination the plugins offer is chosen by default. */
  OK(cadr_renderer_technique(renderer, CADR_TECHNIQUE_KIND_SUBMISSION, &name));
  CHECK(strcmp(name, "groups-mdi-replay") == 0);
  EXPECT(cadr_renderer_technique(renderer, 9, &name), CADR_RESULT_INVALID_ARGUMENT);
  EXPECT(cadr_renderer_technique(renderer, CADR_TECHNIQUE_KIND_VERTEX, NULL),
         CADR_RESULT_NULL_ARGUMENT);

  OK(cadr_scene_bounds(b->scene, &bounds));
  OK(cadr_camera_fit(&bounds, (double)W / H, NULL, &camera));
  EXPECT(cadr_renderer_render(renderer, b->scene, NULL, &stats), CADR_RESULT_NULL_ARGUMENT);
  EXPECT(cadr_renderer_render(renderer, NULL, &camera, &stats), CADR_RESULT_NULL_ARGUMENT);
  EXPECT(cadr_renderer_render(renderer, (CadrScene)renderer, &camera, &stats),
         CADR_RESULT_FOREIGN_HANDLE);
  camera.view[3] = INFINITY;
  EXPECT(cadr_renderer_render(renderer, b->scene, &camera, &stats), CADR_RESULT_INVALID_ARGUMENT);
  MESSAGE_HAS("camera.view[3]");
  OK(cadr_camera_fit(&bounds, (double)W / H, NULL, &camera));
  OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
  CHECK(stats.presented && stats.draws == 2 && stats.triangles == 12 && stats.cpu_us > 0);
  /* The GPU time of each pass of that frame, which make its gpu_us: the count is asked for
     first. */
  {
    size_t pass_count = 0;
    size_t written = 0;
    CadrGpuPassTime passes[32];
    double sum = 0.0;
    int surfaces = 0;
    EXPECT(cadr_renderer_gpu_pass_times(renderer, NULL, 0, &pass_count),
           CADR_RESULT_BUFFER_TOO_SMALL);
    CHECK(pass_count >= 3 && pass_count <= 32);
    EXPECT(cadr_renderer_gpu_pass_times(renderer, passes, 1, &written),
           CADR_RESULT_BUFFER_TOO_SMALL);
    CHECK(written == pass_count);
    EXPECT(cadr_renderer_gpu_pass_times(renderer, passes, 32, NULL), CADR_RESULT_NULL_ARGUMENT);
    EXPECT(cadr_renderer_gpu_pass_times((CadrRenderer)b->scene, passes, 32, &written),
           CADR_RESULT_FOREIGN_HANDLE);
    OK(cadr_renderer_gpu_pass_times(renderer, passes, 32, &written));
    CHECK(written == pass_count);
    for (size_t i = 0; i < written; ++i) {
      CHECK(passes[i].us >= 0.0 && strlen(passes[i].name) > 0);
      sum += passes[i].us;
      surfaces += strcmp(passes[i].name, "surfaces phase 0") == 0;
    }
    CHECK(surfaces == 1 && strcmp(passes[written - 1].name, "techniques after the passes") == 0);
    CHECK(fabs(sum - stats.gpu_us) <= 1e-6 * stats.gpu_us + 0.01);
  }
  OK(cadr_renderer_render(renderer, b->scene, &camera, NULL));

  /* Picking: the cube under the centre with its occurrence path, background in the corner,
     box selection, and every error path. */
  {
    CadrPickResult picked = {sizeof(struct CadrPickResult), NULL, 0};
    OK(cadr_renderer_pick(renderer, b->scene, &camera, W / 2, H / 2, &picked));
    CHECK(picked.hit_count == 1 && picked.hits != NULL);
    CHECK(picked.hits[0].node != 0 && picked.hits[0].path_length >= 2);
    CHECK(picked.hits[0].path[0] == b->root);
    CHECK(picked.hits[0].path[picked.hits[0].path_length - 1] == picked.hits[0].node);
    CHECK(picked.hits[0].depth > 0.0f && picked.hits[0].depth < 1.0f);
    CHECK(picked.hits[0].x == W / 2 && picked.hits[0].y == H / 2);
    CHECK(fabs(picked.hits[0].position[0]) < 1.0 && fabs(picked.hits[0].position[1]) < 1.0);
    cadr_pick_result_free(&picked);
    CHECK(picked.hits == NULL && picked.hit_count == 0);
    cadr_pick_result_free(&picked); /* a zeroed result is a no-op */
    cadr_pick_result_free(NULL);
    OK(cadr_renderer_pick(renderer, b->scene, &camera, 0, 0, &picked));
    CHECK(picked.hit_count == 0 && picked.hits == NULL);
    OK(cadr_renderer_pick_rect(renderer, b->scene, &camera, 0, 0, W, H, &picked));
    CHECK(picked.hit_count >= 1);
    cadr_pick_result_free(&picked);
    EXPECT(cadr_renderer_pick(renderer, b->scene, &camera, W, 0, &picked),
           CADR_RESULT_INVALID_ARGUMENT);
    MESSAGE_HAS("not inside");
    EXPECT(cadr_renderer_pick_rect(renderer, b->scene, &camera, 0, 0, 0, 1, &picked),
           CADR_RESULT_INVALID_ARGUMENT);
    EXPECT(cadr_renderer_pick_rect(renderer, b->scene, &camera, W - 1, 0, 2, 1, &picked),
           CADR_RESULT_INVALID_ARGUMENT);
    EXPECT(cadr_renderer_pick(renderer, b->scene, NULL, 0, 0, &picked), CADR_RESULT_NULL_ARGUMENT);
    EXPECT(cadr_renderer_pick(renderer, b->scene, &camera, 0, 0, NULL), CADR_RESULT_NULL_ARGUMENT);
    EXPECT(cadr_renderer_pick(renderer, NULL, &camera, 0, 0, &picked), CADR_RESULT_NULL_ARGUMENT);
    EXPECT(cadr_renderer_pick(renderer, (CadrScene)renderer, &camera, 0, 0, &picked),
           CADR_RESULT_FOREIGN_HANDLE);
    EXPECT(cadr_renderer_pick((CadrRenderer)b->scene, b->scene, &camera, 0, 0, &picked),
           CADR_RESULT_FOREIGN_HANDLE);
    CHECK(picked.hit_count == 0 && picked.hits == NULL); /* nothing written on failure */
  }

  /* Pixels: wrong sizes are refused, the cube is in the middle. */
  EXPECT(cadr_renderer_read_pixels(renderer, first, W * H * 4 - 1), CADR_RESULT_BUFFER_TOO_SMALL);
  MESSAGE_HAS("24576");
  EXPECT(cadr_renderer_read_pixels(renderer, NULL, W * H * 4), CADR_RESULT_NULL_ARGUMENT);
  OK(cadr_renderer_read_pixels(renderer, first, W * H * 4));
  CHECK(pixel_difference(first, first + 0, 4) == 0);
  {
    const uint8_t *corner = first, *centre = first + ((H / 2) * W + W / 2) * 4;
    CHECK(abs(corner[0] - centre[0]) + abs(corner[1] - centre[1]) + abs(corner[2] - centre[2]) > 30);
  }
  EXPECT(cadr_renderer_save_png(renderer, "/nonexistent/dir/frame.png"), CADR_RESULT_IO);
  MESSAGE_HAS("/nonexistent/dir/frame.png");
  EXPECT(cadr_renderer_save_png(renderer, NULL), CADR_RESULT_NULL_ARGUMENT);

  /* An edit moves the cube; the next frame shows it. */
  translation(matrix, 0.6, 0, 0);
  OK(cadr_scene_set_matrix(b->scene, b->mover, matrix));
  OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
  OK(cadr_renderer_read_pixels(renderer, second, W * H * 4));
  CHECK(pixel_difference(first, second, W * H * 4) > 100);
  translation(matrix, 0, 0, 0);
  OK(cadr_scene_set_matrix(b->scene, b->mover, matrix));

  /* Every kind swapped at run time renders the same image: down to the simplest techniques
   * (culling first: the fast submission needs the fast paths), then back up. */
  for (step = 0; step < 8; ++step) {
    int which = step < 4 ? 1 : 0;
    kind = step < 4 ? 3 - (uint32_t)step : (uint32_t)step - 4;
    OK(cadr_renderer_set_technique(renderer, kind, kinds[kind][which]));
    OK(cadr_renderer_technique(renderer, kind, &name));
    CHECK(strcmp(name, kinds[kind][which]) == 0);
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, second, W * H * 4));
    CHECK(pixel_difference(first, second, W * H * 4) < 20);
  }
  EXPECT(cadr_renderer_set_technique(renderer, CADR_TECHNIQUE_KIND_SUBMISSION, "no-such"),
         CADR_RESULT_NOT_FOUND);
  MESSAGE_HAS("known:");
  EXPECT(cadr_renderer_set_technique(renderer, 7, "none"), CADR_RESULT_INVALID_ARGUMENT);
  EXPECT(cadr_renderer_set_technique(renderer, CADR_TECHNIQUE_KIND_CULLING, NULL),
         CADR_RESULT_NULL_ARGUMENT);
  /* Multi-draw-indirect needs a vertex path that binds the whole scene once. */
  selection.vertex = "per-part";
  selection.submission = "individual-mdi";
  EXPECT(cadr_renderer_check_techniques(renderer, &selection), CADR_RESULT_INVALID_COMBINATION);
  EXPECT(cadr_renderer_set_techniques(renderer, &selection), CADR_RESULT_INVALID_COMBINATION);
  OK(cadr_renderer_technique(renderer, CADR_TECHNIQUE_KIND_VERTEX, &name));
  CHECK(strcmp(name, "arena") == 0); /* the refused selection changed nothing */
  selection.vertex = "pulling";
  OK(cadr_renderer_check_techniques(renderer, &selection));
  OK(cadr_renderer_set_techniques(renderer, &selection));
  OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
  CHECK(stats.draw_calls <= 2 && stats.draws == 2);
  EXPECT(cadr_renderer_set_techniques(renderer, NULL), CADR_RESULT_NULL_ARGUMENT);

  /* Sub-pixel culling (GPU cullers; off by default): a threshold wider than the view culls
   * every part, 0 brings them all back. */
  {
    float pixels = -1.0f;
    uint64_t all;
    struct CadrTechniqueSelection gpu = {sizeof(struct CadrTechniqueSelection), "arena", "ssbo-index", "individual-indirect-count",
                                         "gpu-frustum"};
    pixels = settings_of(renderer).min_pixels;
    CHECK(pixels == 0.0f);
    OK(cadr_renderer_set_techniques(renderer, &gpu));
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    all = stats.triangles;
    CHECK(all > 0);
    OK(SET(renderer, min_pixels, 1.0e6f));
    pixels = settings_of(renderer).min_pixels;
    CHECK(pixels == 1.0e6f);
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    CHECK(stats.triangles == 0);
    OK(SET(renderer, min_pixels, 0.0f));
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    CHECK(stats.triangles == all);
    EXPECT(SET(renderer, min_pixels, -1.0f), CADR_RESULT_INVALID_ARGUMENT);
    MESSAGE_HAS("settings.min_pixels");
    EXPECT(SET(renderer, min_pixels, NAN), CADR_RESULT_INVALID_ARGUMENT);
  }

  /* Level of detail (gpu-clusters; 1 px by default): the coarsest cut draws no more than full
   * detail and never nothing; bad thresholds are refused. */
  {
    float pixels = -1.0f;
    uint64_t full;
    struct CadrTechniqueSelection clusters = {sizeof(struct CadrTechniqueSelection), "arena", "ssbo-index", "individual-indirect-count",
                                              "gpu-clusters"};
    pixels = settings_of(renderer).lod_error;
    CHECK(pixels == 1.0f);
    OK(cadr_renderer_set_techniques(renderer, &clusters));
    OK(SET(renderer, lod_error, 0.0f));
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    full = stats.triangles;
    CHECK(full > 0);
    OK(SET(renderer, lod_error, 1.0e6f));
    pixels = settings_of(renderer).lod_error;
    CHECK(pixels == 1.0e6f);
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    CHECK(stats.triangles > 0 && stats.triangles <= full);
    OK(SET(renderer, lod_error, 1.0f));
    EXPECT(SET(renderer, lod_error, -1.0f), CADR_RESULT_INVALID_ARGUMENT);
    MESSAGE_HAS("settings.lod_error");
    EXPECT(SET(renderer, lod_error, INFINITY), CADR_RESULT_INVALID_ARGUMENT);
  }

  /* Frame replay (on by default): an unchanged second frame resubmits the first's recording
   * and shows the same picture; off, every frame is recorded. */
  {
    CHECK(settings_of(renderer).frame_replay);
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, first, W * H * 4));
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    CHECK(stats.replayed);
    OK(cadr_renderer_read_pixels(renderer, second, W * H * 4));
    CHECK(pixel_difference(first, second, W * H * 4) == 0);
    OK(SET(renderer, frame_replay, false));
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    CHECK(!settings_of(renderer).frame_replay && !stats.replayed);
    OK(SET(renderer, frame_replay, true));
    EXPECT(cadr_renderer_apply_settings((CadrRenderer)b->scene, &applied), CADR_RESULT_FOREIGN_HANDLE);
  }

  /* Frames in flight (offscreen renderers start with 1): with 2, a frame returns once it is
   * submitted and its pixels are read after it finishes; offscreen renderers present nothing. */
  {
    uint32_t frames = 0;
    frames = settings_of(renderer).frames_in_flight;
    CHECK(frames == 1);
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, first, W * H * 4));
    OK(SET(renderer, frames_in_flight, 2));
    frames = settings_of(renderer).frames_in_flight;
    CHECK(frames == 2);
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, second, W * H * 4));
    CHECK(pixel_difference(first, second, W * H * 4) == 0);
    OK(SET(renderer, frames_in_flight, 3));
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, second, W * H * 4));
    CHECK(pixel_difference(first, second, W * H * 4) == 0);
    EXPECT(SET(renderer, frames_in_flight, 4), CADR_RESULT_INVALID_ARGUMENT);
    MESSAGE_HAS("frames in flight");
    EXPECT(SET(renderer, frames_in_flight, 0), CADR_RESULT_INVALID_ARGUMENT);
    OK(SET(renderer, frames_in_flight, 1));
    EXPECT(SET(renderer, present_mode, CADR_PRESENT_MAILBOX), CADR_RESULT_UNSUPPORTED);
    MESSAGE_HAS("without a window");
    CHECK(capabilities_of(renderer).present_modes == 0);
    EXPECT(SET(renderer, present_mode, 7), CADR_RESULT_INVALID_ARGUMENT);
  }

  /* Settings as one sized struct: read, changed, applied; all or nothing; an older host's
   * smaller struct and a newer host's larger one both ways; what the renderer offers. */
  {
    CadrRendererSettings before = settings_of(renderer), older, canary;
    struct {
      CadrRendererSettings settings;
      uint32_t field_of_a_later_version;
    } newer;
    struct CadrFrameStats short_stats;
    CadrRendererCapabilities capabilities = capabilities_of(renderer);
    CHECK(before.size == sizeof before && before.shade_mode == CADR_SHADE_SOLID);
    CHECK(before.frames_in_flight == 1 && before.msaa_samples == 1 && before.lod_error == 1.0f);
    CHECK(before.section_flags == CADR_SECTION_CAPS && before.frame_replay && before.textures);
    CHECK(capabilities.size == sizeof capabilities && (capabilities.msaa_sample_counts & 1u) != 0);
    EXPECT(cadr_renderer_settings(renderer, NULL), CADR_RESULT_NULL_ARGUMENT);
    EXPECT(cadr_renderer_apply_settings(renderer, NULL), CADR_RESULT_NULL_ARGUMENT);
    EXPECT(cadr_renderer_capabilities(renderer, NULL), CADR_RESULT_NULL_ARGUMENT);
    EXPECT(cadr_renderer_settings((CadrRenderer)b->scene, &applied), CADR_RESULT_FOREIGN_HANDLE);
    /* All or nothing: a refused field (here the last one applied) undoes the others. */
    applied = before;
    applied.shade_mode = CADR_SHADE_EDGES;
    applied.ssao = true;
    applied.msaa_samples = 3;
    EXPECT(cadr_renderer_apply_settings(renderer, &applied), CADR_RESULT_INVALID_ARGUMENT);
    MESSAGE_HAS("settings.msaa_samples");
    canary = settings_of(renderer);
    CHECK(settings_equal(&before, &canary));
    applied.size = 2;
    EXPECT(cadr_renderer_apply_settings(renderer, &applied), CADR_RESULT_INVALID_ARGUMENT);
    MESSAGE_HAS("settings->size is 2");
    /* An older host knows the fields up to highlight_style: the rest keep their values. */
    older = before;
    older.size = (uint32_t)offsetof(CadrRendererSettings, highlight_style);
    older.shade_mode = CADR_SHADE_EDGES;
    older.ssao = true; /* beyond its size: not read */
    OK(cadr_renderer_apply_settings(renderer, &older));
    canary = settings_of(renderer);
    CHECK(canary.shade_mode == CADR_SHADE_EDGES && !canary.ssao);
    /* ...and reads only what it knows. */
    memset(&older, 0xAB, sizeof older);
    older.size = (uint32_t)offsetof(CadrRendererSettings, highlight_style);
    OK(cadr_renderer_settings(renderer, &older));
    CHECK(older.shade_mode == CADR_SHADE_EDGES && older.highlight_style == 0xABABABABu);
    /* A newer host: its unknown field zeroed when read, accepted at 0, refused otherwise. */
    memset(&newer, 0xCD, sizeof newer);
    newer.settings.size = sizeof newer;
    OK(cadr_renderer_settings(renderer, &newer.settings));
    CHECK(newer.field_of_a_later_version == 0 && newer.settings.size == sizeof newer);
    newer.settings.shade_mode = CADR_SHADE_SOLID;
    OK(cadr_renderer_apply_settings(renderer, &newer.settings));
    canary = settings_of(renderer);
    CHECK(settings_equal(&before, &canary));
    newer.field_of_a_later_version = 1;
    EXPECT(cadr_renderer_apply_settings(renderer, &newer.settings), CADR_RESULT_INVALID_ARGUMENT);
    MESSAGE_HAS("does not know");
    /* Output structs of older hosts: frame statistics up to `size` only. */
    memset(&short_stats, 0xEE, sizeof short_stats);
    short_stats.size = (uint32_t)offsetof(struct CadrFrameStats, cpu_record_us);
    OK(cadr_renderer_render(renderer, b->scene, &camera, &short_stats));
    CHECK(short_stats.presented && short_stats.cpu_us > 0.0);
    CHECK(short_stats.draw_calls == 0xEEEEEEEEEEEEEEEEull);
    short_stats.size = 0;
    EXPECT(cadr_renderer_render(renderer, b->scene, &camera, &short_stats),
           CADR_RESULT_INVALID_ARGUMENT);
    MESSAGE_HAS("stats->size is 0");
  }

  /* Shade modes. */
  mode = settings_of(renderer).shade_mode;
  CHECK(mode == CADR_SHADE_SOLID);
  OK(SET(renderer, shade_mode, CADR_SHADE_EDGES));
  mode = settings_of(renderer).shade_mode;
  CHECK(mode == CADR_SHADE_EDGES);
  OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
  OK(SET(renderer, shade_mode, CADR_SHADE_HIDDEN_LINE));
  OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
  OK(SET(renderer, shade_mode, CADR_SHADE_WIREFRAME));
  OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
  mode = settings_of(renderer).shade_mode;
  CHECK(mode == CADR_SHADE_WIREFRAME);
  /* X-ray with either transparency method: the fast one (the default) and the exact one. */
  OK(SET(renderer, shade_mode, CADR_SHADE_XRAY));
  OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
  OK(cadr_renderer_technique(renderer, CADR_TECHNIQUE_KIND_TRANSPARENCY, &name));
  CHECK(strcmp(name, "weighted-blended") == 0);
  OK(cadr_renderer_set_technique(renderer, CADR_TECHNIQUE_KIND_TRANSPARENCY, "per-pixel-lists"));
  OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
  OK(cadr_renderer_technique(renderer, CADR_TECHNIQUE_KIND_TRANSPARENCY, &name));
  CHECK(strcmp(name, "per-pixel-lists") == 0);
  mode = settings_of(renderer).shade_mode;
  CHECK(mode == CADR_SHADE_XRAY);
  OK(cadr_renderer_set_technique(renderer, CADR_TECHNIQUE_KIND_TRANSPARENCY, "weighted-blended"));
  EXPECT(SET(renderer, shade_mode, 5), CADR_RESULT_INVALID_ARGUMENT);
  MESSAGE_HAS("4 (X-ray)");
  OK(SET(renderer, shade_mode, CADR_SHADE_SOLID));

  /* Section planes: a plane keeping only z >= 1e6 cuts the whole scene away, so nothing is
   * drawn or picked; planes are refused with the reason and kept; no planes cut nothing. */
  {
    double away[4] = {0.0, 0.0, 2.0, -2.0e6}, read[8] = {0};
    double zero_normal[4] = {0.0, 0.0, 0.0, 1.0};
    double seven[28] = {0};
    float blue[4] = {0.1f, 0.2f, 0.9f, 1.0f}, not_finite[4] = {NAN, 0.0f, 0.0f, 1.0f};
    uint32_t count = 9, flags = 0;
    CadrPickResult picked = {sizeof(struct CadrPickResult), NULL, 0};
    OK(cadr_renderer_section_planes(renderer, NULL, 0, &count));
    CHECK(count == 0);
    flags = settings_of(renderer).section_flags;
    CHECK(flags == CADR_SECTION_CAPS);
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, first, W * H * 4));
    OK(cadr_renderer_set_section_planes(renderer, away, 1));
    OK(cadr_renderer_section_planes(renderer, read, 2, &count));
    CHECK(count == 1 && read[2] == 1.0 && read[3] == -1.0e6 && read[4] == 0.0);
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, second, W * H * 4));
    CHECK(pixel_difference(first, second, W * H * 4) > 0);
    /* The centre shows the background, as the left edge of its row does (a vertical gradient). */
    CHECK(second[4 * (W * (H / 2) + W / 2)] == second[4 * (W * (H / 2))]);
    OK(cadr_renderer_pick(renderer, b->scene, &camera, W / 2, H / 2, &picked));
    CHECK(picked.hit_count == 0);
    EXPECT(cadr_renderer_set_section_planes(renderer, zero_normal, 1), CADR_RESULT_INVALID_ARGUMENT);
    MESSAGE_HAS("section plane 0");
    EXPECT(cadr_renderer_set_section_planes(renderer, seven, 7), CADR_RESULT_INVALID_ARGUMENT);
    MESSAGE_HAS("at most 6");
    EXPECT(cadr_renderer_set_section_planes(renderer, NULL, 1), CADR_RESULT_NULL_ARGUMENT);
    OK(cadr_renderer_section_planes(renderer, NULL, 0, &count));
    CHECK(count == 1); /* refused planes leave the planes as they were */
    EXPECT(cadr_renderer_section_planes(renderer, read, 2, NULL), CADR_RESULT_NULL_ARGUMENT);
    OK(SET(renderer, section_flags, CADR_SECTION_CAPS | CADR_SECTION_HATCHED));
    flags = settings_of(renderer).section_flags;
    CHECK(flags == (CADR_SECTION_CAPS | CADR_SECTION_HATCHED));
    EXPECT(SET(renderer, section_flags, 8), CADR_RESULT_INVALID_ARGUMENT);
    MESSAGE_HAS("unknown bits");
    applied = settings_of(renderer);
    memcpy(applied.section_cap_colors[5], blue, sizeof blue);
    OK(cadr_renderer_apply_settings(renderer, &applied));
    CHECK(settings_of(renderer).section_cap_colors[5][2] == 0.9f);
    memcpy(applied.section_cap_colors[0], not_finite, sizeof not_finite);
    EXPECT(cadr_renderer_apply_settings(renderer, &applied), CADR_RESULT_INVALID_ARGUMENT);
    MESSAGE_HAS("section_cap_colors[0]");
    OK(cadr_renderer_set_section_planes(renderer, NULL, 0));
    OK(SET(renderer, section_flags, CADR_SECTION_CAPS));
    OK(cadr_renderer_pick(renderer, b->scene, &camera, W / 2, H / 2, &picked));
    CHECK(picked.hit_count == 1);
    cadr_pick_result_free(&picked);
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, second, W * H * 4));
    CHECK(pixel_difference(first, second, W * H * 4) == 0);
  }

  /* The background: a red-to-blue gradient shows at the top and bottom corners, refused colours
   * name the problem and leave it as it was, and the default comes back. */
  {
    float top[3] = {1.0f, 0.0f, 0.0f}, bottom[3] = {0.0f, 0.0f, 1.0f};
    float too_bright[3] = {1.5f, 0.0f, 0.0f}, not_finite[3] = {NAN, 0.0f, 0.0f};
    float default_top[3], default_bottom[3], read_top[3], read_bottom[3];
    const uint8_t *corner;
    get_background(renderer, default_top, default_bottom);
    CHECK(default_top[0] > 0.5f && default_top[0] <= 1.0f && default_bottom[2] > 0.5f);
    OK(set_background(renderer, top, bottom));
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, second, W * H * 4));
    corner = second; /* top-left */
    CHECK(corner[0] > 240 && corner[1] < 10 && corner[2] < 15);
    corner = second + 4 * (W * (H - 1)); /* bottom-left */
    CHECK(corner[0] < 15 && corner[1] < 10 && corner[2] > 240);
    EXPECT(set_background(renderer, too_bright, bottom), CADR_RESULT_INVALID_ARGUMENT);
    MESSAGE_HAS("background top colour");
    EXPECT(set_background(renderer, top, not_finite), CADR_RESULT_INVALID_ARGUMENT);
    MESSAGE_HAS("background bottom colour");
    get_background(renderer, read_top, read_bottom);
    CHECK(read_top[0] == 1.0f && read_top[2] == 0.0f && read_bottom[2] == 1.0f);
    OK(set_background(renderer, default_top, default_bottom));
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, second, W * H * 4));
    CHECK(pixel_difference(first, second, W * H * 4) == 0);
  }

  /* Anti-aliasing: one sample by default and the offered levels as a mask (1 always); a level
   * the device lacks is refused by name; the highest offered level blends edge pixels, keeps
   * the rest of the picture and picks exactly; one sample again draws the first picture. */
  {
    uint32_t samples = 0, offered = 0, highest = 1, bit, differing;
    CadrPickResult picked = {sizeof(struct CadrPickResult), NULL, 0};
    samples = settings_of(renderer).msaa_samples;
    offered = capabilities_of(renderer).msaa_sample_counts;
    CHECK(samples == 1 && (offered & 1u) != 0);
    for (bit = 2; bit <= 64; bit <<= 1) {
      if (offered & bit) {
        highest = bit;
      }
    }
    CHECK(highest >= 4); /* lavapipe offers 4x, GPUs more */
    EXPECT(SET(renderer, msaa_samples, 3), CADR_RESULT_INVALID_ARGUMENT);
    MESSAGE_HAS("MSAA 3x");
    samples = settings_of(renderer).msaa_samples;
    CHECK(samples == 1);
    OK(SET(renderer, msaa_samples, highest));
    samples = settings_of(renderer).msaa_samples;
    CHECK(samples == highest);
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, second, W * H * 4));
    differing = pixel_difference(first, second, W * H * 4);
    CHECK(differing > 0 && differing < W * H / 10);
    OK(cadr_renderer_pick(renderer, b->scene, &camera, W / 2, H / 2, &picked));
    CHECK(picked.hit_count == 1);
    cadr_pick_result_free(&picked);
    OK(SET(renderer, msaa_samples, 1));
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, second, W * H * 4));
    CHECK(pixel_difference(first, second, W * H * 4) == 0);
  }

  /* Dashed hidden lines: off by default; on, the hidden-line picture gains dashes. */
  {
    bool dashed = true;
    dashed = settings_of(renderer).dashed_hidden_lines;
    CHECK(!dashed);
    OK(SET(renderer, shade_mode, CADR_SHADE_HIDDEN_LINE));
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, first, W * H * 4));
    OK(SET(renderer, dashed_hidden_lines, true));
    dashed = settings_of(renderer).dashed_hidden_lines;
    CHECK(dashed);
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, second, W * H * 4));
    CHECK(pixel_difference(first, second, W * H * 4) > 0);
    OK(SET(renderer, dashed_hidden_lines, false));
    OK(SET(renderer, shade_mode, CADR_SHADE_SOLID));
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, first, W * H * 4));
  }

  /* Silhouettes: on by default; in hidden-line they outline the engine's curved surfaces beside
   * its feature edges, in solid they change nothing. */
  {
    CadrScene engine = NULL;
    CadrNode engine_root = 0;
    struct CadrLoadResult loaded = {.size = sizeof(struct CadrLoadResult)};
    struct CadrBounds bounds;
    struct CadrCamera engine_camera;
    const double front[3] = {0.4, 0.5, 1.0};
    bool on = false;
    OK(cadr_scene_create(&engine));
    OK(cadr_scene_root(engine, &engine_root));
    memset(&loaded, 0, sizeof loaded);
    loaded.size = sizeof loaded;
    OK(cadr_scene_load(engine,
                       "/usr/share/assimp/models/glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb",
                       engine_root, &loaded));
    cadr_load_result_free(&loaded);
    OK(cadr_scene_bounds(engine, &bounds));
    OK(cadr_camera_fit(&bounds, (double)W / H, front, &engine_camera));
    on = settings_of(renderer).silhouettes;
    CHECK(on);
    OK(SET(renderer, shade_mode, CADR_SHADE_HIDDEN_LINE));
    OK(cadr_renderer_render(renderer, engine, &engine_camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, second, W * H * 4));
    OK(SET(renderer, silhouettes, false));
    on = settings_of(renderer).silhouettes;
    CHECK(!on);
    OK(cadr_renderer_render(renderer, engine, &engine_camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, first, W * H * 4));
    CHECK(pixel_difference(first, second, W * H * 4) > 20);
    OK(SET(renderer, shade_mode, CADR_SHADE_SOLID));
    OK(cadr_renderer_render(renderer, engine, &engine_camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, first, W * H * 4));
    OK(SET(renderer, silhouettes, true));
    OK(cadr_renderer_render(renderer, engine, &engine_camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, second, W * H * 4));
    CHECK(pixel_difference(first, second, W * H * 4) == 0);
    OK(cadr_scene_destroy(engine));
    /* The blocks below compare with the test scene's solid picture. */
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, first, W * H * 4));
  }

  /* Highlight styles: tint by default; the outline keeps the cube's colours and adds an orange
   * band around it; with nothing highlighted it draws nothing. */
  {
    uint32_t style = 7;
    size_t i;
    int orange = 0;
    uint8_t *tinted = (uint8_t *)malloc(W * H * 4);
    CHECK(tinted != NULL);
    style = settings_of(renderer).highlight_style;
    CHECK(style == CADR_HIGHLIGHT_TINT);
    EXPECT(SET(renderer, highlight_style, 7), CADR_RESULT_INVALID_ARGUMENT);
    MESSAGE_HAS("settings.highlight_style 7");
    OK(cadr_scene_set_flags(b->scene, b->geo,
                            CADR_NODE_VISIBLE | CADR_NODE_PICKABLE | CADR_NODE_HIGHLIGHTED));
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, tinted, W * H * 4));
    CHECK(pixel_difference(first, tinted, W * H * 4) > 0);
    OK(SET(renderer, highlight_style, CADR_HIGHLIGHT_OUTLINE));
    style = settings_of(renderer).highlight_style;
    CHECK(style == CADR_HIGHLIGHT_OUTLINE);
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, second, W * H * 4));
    CHECK(pixel_difference(tinted, second, W * H * 4) > 0);
    for (i = 0; i < (size_t)W * H * 4; i += 4) {
      orange += second[i] > 200 && second[i + 1] > 100 && second[i + 1] < 180 && second[i + 2] < 60 &&
                !(first[i] > 200 && first[i + 1] > 100 && first[i + 1] < 180 && first[i + 2] < 60);
    }
    CHECK(orange > 10);
    OK(cadr_scene_set_flags(b->scene, b->geo, CADR_NODE_VISIBLE | CADR_NODE_PICKABLE));
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, second, W * H * 4));
    CHECK(pixel_difference(first, second, W * H * 4) == 0);
    OK(SET(renderer, highlight_style, CADR_HIGHLIGHT_TINT));
    free(tinted);
  }

  /* The palette: edge lines in the host's colour; highlighted parts outlined in its highlight
   * colour, the band as wide as asked; out-of-range values refused, the old ones kept. */
  {
    float rgb[3] = {-1.0f, -1.0f, -1.0f};
    const float blue[3] = {0.0f, 0.0f, 1.0f};
    const float green[3] = {0.0f, 1.0f, 0.0f};
    const float too_bright[3] = {2.0f, 0.0f, 0.0f};
    uint32_t width = 0;
    size_t i;
    int blue_pixels = 0, narrow = 0, wide = 0;
    get_rgb(renderer, offsetof(CadrRendererSettings, edge_color), rgb);
    CHECK(rgb[0] > 0.05f && rgb[0] < 0.07f && rgb[2] > 0.08f && rgb[2] < 0.1f);
    get_rgb(renderer, offsetof(CadrRendererSettings, highlight_color), rgb);
    CHECK(rgb[0] == 1.0f && rgb[1] > 0.5f && rgb[1] < 0.6f);
    width = settings_of(renderer).outline_width;
    CHECK(width == 2);
    EXPECT(SET_RGB(renderer, edge_color, too_bright), CADR_RESULT_INVALID_ARGUMENT);
    MESSAGE_HAS("edge colour");
    EXPECT(SET(renderer, outline_width, 9), CADR_RESULT_INVALID_ARGUMENT);
    MESSAGE_HAS("outline width 9");
    EXPECT(SET(renderer, outline_width, 0), CADR_RESULT_INVALID_ARGUMENT);
    width = settings_of(renderer).outline_width;
    CHECK(width == 2);

    OK(SET_RGB(renderer, edge_color, blue));
    get_rgb(renderer, offsetof(CadrRendererSettings, edge_color), rgb);
    CHECK(rgb[0] == 0.0f && rgb[1] == 0.0f && rgb[2] == 1.0f);
    OK(SET(renderer, shade_mode, CADR_SHADE_EDGES));
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, second, W * H * 4));
    for (i = 0; i < (size_t)W * H * 4; i += 4) {
      blue_pixels += second[i] == 0 && second[i + 1] == 0 && second[i + 2] == 255;
    }
    CHECK(blue_pixels > 10);
    OK(SET(renderer, shade_mode, CADR_SHADE_SOLID));

    OK(SET_RGB(renderer, highlight_color, green));
    OK(SET(renderer, highlight_style, CADR_HIGHLIGHT_OUTLINE));
    OK(cadr_scene_set_flags(b->scene, b->geo,
                            CADR_NODE_VISIBLE | CADR_NODE_PICKABLE | CADR_NODE_HIGHLIGHTED));
    OK(SET(renderer, outline_width, 1));
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, second, W * H * 4));
    for (i = 0; i < (size_t)W * H * 4; i += 4) {
      narrow += second[i] == 0 && second[i + 1] == 255 && second[i + 2] == 0;
    }
    OK(SET(renderer, outline_width, 4));
    width = settings_of(renderer).outline_width;
    CHECK(width == 4);
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, second, W * H * 4));
    for (i = 0; i < (size_t)W * H * 4; i += 4) {
      wide += second[i] == 0 && second[i + 1] == 255 && second[i + 2] == 0;
    }
    CHECK(narrow > 10);
    CHECK(wide > 3 * narrow);

    /* The defaults again draw the test scene's solid picture. */
    {
      const float edges[3] = {0.06f, 0.07f, 0.09f};
      const float orange[3] = {1.0f, 0.55f, 0.05f};
      OK(SET_RGB(renderer, edge_color, edges));
      OK(SET_RGB(renderer, highlight_color, orange));
    }
    OK(SET(renderer, outline_width, 2));
    OK(SET(renderer, highlight_style, CADR_HIGHLIGHT_TINT));
    OK(cadr_scene_set_flags(b->scene, b->geo, CADR_NODE_VISIBLE | CADR_NODE_PICKABLE));
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, second, W * H * 4));
    CHECK(pixel_difference(first, second, W * H * 4) == 0);
  }

  /* Ambient occlusion: off by default; on, it only darkens, and off again restores the picture. */
  {
    bool on = true;
    size_t i;
    int lighter = 0;
    on = settings_of(renderer).ssao;
    CHECK(!on);
    OK(SET(renderer, ssao, true));
    on = settings_of(renderer).ssao;
    CHECK(on);
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, second, W * H * 4));
    for (i = 0; i < (size_t)W * H * 4; i += 4) {
      int before = first[i] + first[i + 1] + first[i + 2];
      int after = second[i] + second[i + 1] + second[i + 2];
      lighter += after > before + 3;
    }
    CHECK(lighter == 0);
    OK(SET(renderer, ssao, false));
    OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, second, W * H * 4));
    CHECK(pixel_difference(first, second, W * H * 4) == 0);
  }

  /* Textures: a file's base-colour texture is drawn by default; off, the box shows its base
   * colour only; on again, the first picture. */
  {
    CadrScene textured = NULL;
    CadrNode textured_root = 0;
    struct CadrLoadResult loaded = {.size = sizeof(struct CadrLoadResult)};
    struct CadrBounds box;
    struct CadrCamera box_camera;
    const double front[3] = {0.4, 0.5, 1.0};
    bool on = false;
    uint8_t *with = (uint8_t *)malloc(W * H * 4), *without = (uint8_t *)malloc(W * H * 4);
    CHECK(with != NULL && without != NULL);
    OK(cadr_scene_create(&textured));
    OK(cadr_scene_root(textured, &textured_root));
    memset(&loaded, 0, sizeof loaded);
    loaded.size = sizeof loaded;
    OK(cadr_scene_load(textured,
                       "/usr/share/assimp/models/glTF2/BoxTextured-glTF-Binary/BoxTextured.glb",
                       textured_root, &loaded));
    cadr_load_result_free(&loaded);
    OK(cadr_scene_bounds(textured, &box));
    OK(cadr_camera_fit(&box, (double)W / H, front, &box_camera));
    on = settings_of(renderer).textures;
    CHECK(on);
    OK(cadr_renderer_render(renderer, textured, &box_camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, with, W * H * 4));
    OK(SET(renderer, textures, false));
    on = settings_of(renderer).textures;
    CHECK(!on);
    OK(cadr_renderer_render(renderer, textured, &box_camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, without, W * H * 4));
    CHECK(pixel_difference(with, without, W * H * 4) > 200);
    OK(SET(renderer, textures, true));
    OK(cadr_renderer_render(renderer, textured, &box_camera, &stats));
    OK(cadr_renderer_read_pixels(renderer, without, W * H * 4));
    CHECK(pixel_difference(with, without, W * H * 4) == 0);
    OK(cadr_scene_destroy(textured));
    free(with);
    free(without);
  }

  test_host_textures(renderer, W, H);

  /* Picking through translucent parts: off by default; on, the opaque cubes still stop it. */
  {
    bool through = true;
    CadrPickResult picked = {sizeof(struct CadrPickResult), NULL, 0};
    through = settings_of(renderer).pick_through_translucent;
    CHECK(!through);
    OK(SET(renderer, pick_through_translucent, true));
    through = settings_of(renderer).pick_through_translucent;
    CHECK(through);
    OK(cadr_renderer_pick(renderer, b->scene, &camera, W / 2, H / 2, &picked));
    CHECK(picked.hit_count == 1);
    cadr_pick_result_free(&picked);
    OK(SET(renderer, pick_through_translucent, false));
  }

  /* Resizing. */
  OK(cadr_renderer_resize(renderer, 48, 32));
  OK(cadr_renderer_size(renderer, &width, &height));
  CHECK(width == 48 && height == 32);
  EXPECT(cadr_renderer_resize(renderer, 0, 32), CADR_RESULT_INVALID_ARGUMENT);
  OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));
  EXPECT(cadr_renderer_read_pixels(renderer, second, 48 * 32 * 4 - 4), CADR_RESULT_BUFFER_TOO_SMALL);
  OK(cadr_renderer_read_pixels(renderer, second, 48 * 32 * 4));

  /* A second renderer draws the same scene (uploaded afresh), then the first again. */
  OK(cadr_renderer_create(context, W, H, &other));
  OK(cadr_renderer_render(other, b->scene, &camera, &stats));
  OK(cadr_renderer_read_pixels(other, second, W * H * 4));
  CHECK(pixel_difference(first, second, W * H * 4) < 20);
  OK(cadr_renderer_render(renderer, b->scene, &camera, &stats));

  /* Destroyed and foreign renderer handles; destroy(NULL). */
  OK(cadr_renderer_destroy(other));
  EXPECT(cadr_renderer_destroy(other), CADR_RESULT_DESTROYED_HANDLE);
  EXPECT(cadr_renderer_render(other, b->scene, &camera, &stats), CADR_RESULT_DESTROYED_HANDLE);
  EXPECT(cadr_renderer_destroy((CadrRenderer)context), CADR_RESULT_FOREIGN_HANDLE);
  OK(cadr_renderer_destroy(NULL));
  OK(cadr_renderer_destroy(renderer));
  free(first);
  free(second);
}

/* Without any plugin library a context still has the built-in techniques, and a renderer
   draws with them. */
/* Frames exported for another API: every frame copied into memory given as a file
 * descriptor, which holds the frame's pixels as read_pixels gives them; new memory, of a new
 * generation, after a resize; refusals for renderers made otherwise. */
static void test_export(CadrContext context, struct Built *b) {
  enum { W = 64, H = 48 };
  CadrRenderer exporting = NULL, plain = NULL;
  struct CadrCamera camera;
  struct CadrBounds bounds;
  CadrExportedFrame frame;
  EXPECT(cadr_renderer_create_for_export(context, 0, H, &exporting), CADR_RESULT_INVALID_ARGUMENT);
  EXPECT(cadr_renderer_create_for_export(context, W, H, NULL), CADR_RESULT_NULL_ARGUMENT);
  EXPECT(cadr_renderer_create_for_export((CadrContext)b->scene, W, H, &exporting),
         CADR_RESULT_FOREIGN_HANDLE);
  {
    /* The exported memory counts in the context's device memory: an exporting renderer holds
     * at least a frame's bytes more than a plain one of its size. */
    struct CadrMemoryUsage usage;
    uint64_t before, with_export, with_plain;
    memset(&usage, 0, sizeof usage);
    usage.size = sizeof usage;
    OK(cadr_context_memory_usage(context, &usage));
    before = usage.device_allocated_bytes;
    OK(cadr_renderer_create_for_export(context, W, H, &exporting));
    OK(cadr_context_memory_usage(context, &usage));
    with_export = usage.device_allocated_bytes;
    OK(cadr_renderer_create(context, W, H, &plain));
    OK(cadr_context_memory_usage(context, &usage));
    with_plain = usage.device_allocated_bytes;
    CHECK(with_export - before >= (with_plain - with_export) + (uint64_t)W * H * 4);
    OK(cadr_renderer_destroy(plain));
    plain = NULL;
  }
  OK(cadr_scene_bounds(b->scene, &bounds));
  OK(cadr_camera_fit(&bounds, (double)W / H, NULL, &camera));
  OK(cadr_renderer_render(exporting, b->scene, &camera, NULL));
  memset(&frame, 0, sizeof frame);
  frame.size = sizeof frame;
  OK(cadr_renderer_exported_frame(exporting, &frame));
  CHECK(frame.fd >= 0 && frame.width == W && frame.height == H && frame.row_bytes == W * 4);
  CHECK(frame.allocation_size >= (uint64_t)W * H * 4 && frame.generation == 1);
  {
    /* The UUIDs an importer compares with its own: the device's and the driver's. */
    static const uint8_t zero[16] = {0};
    CHECK(memcmp(frame.device_uuid, zero, 16) != 0 && memcmp(frame.driver_uuid, zero, 16) != 0);
  }
  /* The descriptor is open and the host's; its memory is the driver's own format (an opaque
   * descriptor: OpenGL imports it, tests/tests/c_samples.rs compares what it shows). */
  CHECK(fcntl(frame.fd, F_GETFD) != -1);
  close(frame.fd);
  /* Resized: new memory, a new generation. */
  OK(cadr_renderer_resize(exporting, W / 2, H / 2));
  OK(cadr_renderer_render(exporting, b->scene, &camera, NULL));
  OK(cadr_renderer_exported_frame(exporting, &frame));
  CHECK(frame.width == W / 2 && frame.height == H / 2 && frame.generation == 2);
  CHECK(frame.depth_offset == 0 && frame.depth_row_bytes == 0);
  close(frame.fd);
  /* The depth after the colour (1.1): new memory as soon as it is asked for, of a new
   * generation, with room for the depth at an aligned offset; rendering goes on into it. */
  OK(SET(exporting, depth_to_host, true));
  CHECK(settings_of(exporting).depth_to_host);
  OK(cadr_renderer_exported_frame(exporting, &frame));
  CHECK(frame.generation == 3 && frame.depth_offset % 256 == 0 &&
        frame.depth_offset >= (uint64_t)frame.row_bytes * frame.height &&
        frame.depth_row_bytes == frame.width * 4);
  CHECK(frame.allocation_size >= frame.depth_offset + (uint64_t)frame.depth_row_bytes * frame.height);
  close(frame.fd);
  OK(cadr_renderer_render(exporting, b->scene, &camera, NULL));
  {
    /* A 1.0 host's struct ends before the depth's fields: they are not written. */
    CadrExportedFrame older;
    memset(&older, 0xAB, sizeof older);
    older.size = (uint32_t)offsetof(CadrExportedFrame, depth_offset);
    OK(cadr_renderer_exported_frame(exporting, &older));
    CHECK(older.generation == 3 && older.depth_offset == 0xABABABABABABABABull);
    close(older.fd);
  }
  OK(SET(exporting, depth_to_host, false));
  OK(cadr_renderer_exported_frame(exporting, &frame));
  CHECK(frame.generation == 4 && frame.depth_offset == 0);
  close(frame.fd);
  EXPECT(cadr_renderer_exported_frame(exporting, NULL), CADR_RESULT_NULL_ARGUMENT);
  frame.size = 2;
  EXPECT(cadr_renderer_exported_frame(exporting, &frame), CADR_RESULT_INVALID_ARGUMENT);
  OK(cadr_renderer_create(context, W, H, &plain));
  frame.size = sizeof frame;
  EXPECT(cadr_renderer_exported_frame(plain, &frame), CADR_RESULT_INVALID_ARGUMENT);
  MESSAGE_HAS("cadr_renderer_create_for_export");
  {
    /* Any renderer keeps its frames' depth on request, read back with
     * cadr_renderer_read_depth (1.1): none while the setting is off or before a frame kept
     * it; then 0..1, the background at 1. */
    const size_t bytes = (size_t)W * H * sizeof(float);
    float *depth = (float *)malloc(bytes);
    size_t i, near = 0, background = 0, outside = 0;
    CHECK(depth != NULL);
    EXPECT(cadr_renderer_read_depth(plain, depth, bytes), CADR_RESULT_INVALID_ARGUMENT);
    MESSAGE_HAS("depth_to_host");
    OK(SET(plain, depth_to_host, true));
    CHECK(settings_of(plain).depth_to_host);
    EXPECT(cadr_renderer_read_depth(plain, depth, bytes), CADR_RESULT_INVALID_ARGUMENT);
    MESSAGE_HAS("no frame kept its depth");
    OK(cadr_renderer_render(plain, b->scene, &camera, NULL));
    EXPECT(cadr_renderer_read_depth(plain, NULL, bytes), CADR_RESULT_NULL_ARGUMENT);
    EXPECT(cadr_renderer_read_depth(plain, depth, bytes - 1), CADR_RESULT_BUFFER_TOO_SMALL);
    EXPECT(cadr_renderer_read_depth((CadrRenderer)b->scene, depth, bytes),
           CADR_RESULT_FOREIGN_HANDLE);
    OK(cadr_renderer_read_depth(plain, depth, bytes));
    for (i = 0; i < (size_t)W * H; ++i) {
      near += depth[i] < 1.0f;
      background += depth[i] == 1.0f;
      outside += !(depth[i] >= 0.0f && depth[i] <= 1.0f);
    }
    CHECK(near > 0 && background > 0 && outside == 0);
    free(depth);
  }
  OK(cadr_renderer_destroy(plain));
  {
    /* The settings' functions on a destroyed renderer. */
    CadrRendererSettings settings;
    CadrRendererCapabilities capabilities;
    float depth[4];
    memset(&settings, 0, sizeof settings);
    settings.size = sizeof settings;
    memset(&capabilities, 0, sizeof capabilities);
    capabilities.size = sizeof capabilities;
    EXPECT(cadr_renderer_read_depth(plain, depth, sizeof depth), CADR_RESULT_DESTROYED_HANDLE);
    EXPECT(cadr_renderer_settings(plain, &settings), CADR_RESULT_DESTROYED_HANDLE);
    EXPECT(cadr_renderer_apply_settings(plain, &settings), CADR_RESULT_DESTROYED_HANDLE);
    EXPECT(cadr_renderer_capabilities(plain, &capabilities), CADR_RESULT_DESTROYED_HANDLE);
    EXPECT(cadr_renderer_capabilities((CadrRenderer)b->scene, &capabilities),
           CADR_RESULT_FOREIGN_HANDLE);
  }
  OK(cadr_renderer_destroy(exporting));
  EXPECT(cadr_renderer_exported_frame(exporting, &frame), CADR_RESULT_DESTROYED_HANDLE);
}

/* Draws a red cube in a new scene whose geometry memory limit is `limit` (UINT64_MAX: the
 * default, kept in memory) into `pixels`; returns the statistics after the frame. */
/* Renders `scene` with the camera fitted to it, reads the pixels, and destroys it; returns its
 * statistics. */
static struct CadrSceneStatistics draw_fitted_and_destroy(CadrRenderer renderer, CadrScene scene,
                                                          uint8_t *pixels, size_t bytes,
                                                          struct CadrFrameStats *stats) {
  struct CadrSceneStatistics statistics = {.size = sizeof(struct CadrSceneStatistics)};
  struct CadrBounds bounds;
  CadrCamera camera;

  OK(cadr_scene_bounds(scene, &bounds));
  OK(cadr_camera_fit(&bounds, 1.0, NULL, &camera));
  OK(cadr_renderer_render(renderer, scene, &camera, stats));
  OK(cadr_renderer_read_pixels(renderer, pixels, bytes));
  OK(cadr_scene_statistics(scene, &statistics));
  OK(cadr_scene_destroy(scene));
  return statistics;
}

static struct CadrSceneStatistics draw_cube_with_limit(CadrRenderer renderer, uint64_t limit,
                                                       uint8_t *pixels, size_t bytes,
                                                       struct CadrFrameStats *stats) {
  CadrScene scene;
  CadrNode root, geo;
  CadrGeometry cube;
  CadrMaterial parts[2];
  struct CadrGeometryDesc desc = cube_desc();
  struct CadrMaterialDesc red = {sizeof(struct CadrMaterialDesc), "red", {0.8f, 0.1f, 0.1f, 1.0f}, 0.0f, 0.5f};
  struct CadrBounds bounds;

  OK(cadr_scene_create(&scene));
  OK(cadr_scene_root(scene, &root));
  if (limit != UINT64_MAX) OK(cadr_scene_set_geometry_memory_limit(scene, limit));
  OK(cadr_scene_create_geometry(scene, &desc, &cube));
  OK(cadr_scene_geometry_bounds(scene, cube, &bounds));
  CHECK(bounds.min[0] == -0.5 && bounds.max[2] == 0.5);
  OK(cadr_scene_create_material(scene, &red, &parts[0]));
  parts[1] = parts[0];
  OK(cadr_scene_create_geo(scene, "cube", cube, parts, 2, &geo));
  OK(cadr_scene_add_child(scene, root, geo));
  return draw_fitted_and_destroy(renderer, scene, pixels, bytes, stats);
}

/* Loads gen:fine (two units of their own parts) into a new scene with the geometry memory
 * limit given, renders it fitted and reads the pixels; returns its statistics. */
static struct CadrSceneStatistics draw_loaded_with_limit(CadrRenderer renderer, uint64_t limit,
                                                         uint8_t *pixels, size_t bytes) {
  CadrScene scene;
  CadrNode root;
  struct CadrLoadResult loaded = {.size = sizeof(struct CadrLoadResult)};

  OK(cadr_scene_create(&scene));
  OK(cadr_scene_root(scene, &root));
  if (limit != UINT64_MAX) OK(cadr_scene_set_geometry_memory_limit(scene, limit));
  OK(cadr_scene_load(scene, "gen:fine:units=2,detail=1,unique=1", root, &loaded));
  CHECK(loaded.geometry_count == 10);
  cadr_load_result_free(&loaded);
  return draw_fitted_and_destroy(renderer, scene, pixels, bytes, NULL);
}

/* A scene that keeps its geometry in its page file (the limit at 0) reports it there, draws
 * the picture a scene keeping it in memory draws, and says what the GPU holds. */
static void test_page_file(CadrContext context) {
  enum { S = 48 };
  CadrRenderer renderer;
  uint8_t in_memory[S * S * 4], paged[S * S * 4];
  struct CadrFrameStats stats = {.size = sizeof(struct CadrFrameStats)};
  struct CadrSceneStatistics statistics;

  OK(cadr_renderer_create(context, S, S, &renderer));
  statistics = draw_cube_with_limit(renderer, UINT64_MAX, in_memory, sizeof in_memory, &stats);
  CHECK(statistics.paged_geometries == 0 && statistics.paged_geometry_bytes == 0);
  CHECK(statistics.resident_geometry_bytes >= 8 * 24 + 36 * 4);
  CHECK(stats.resident_bytes > 0 && stats.streaming_budget == 0 && stats.streamed_bytes == 0);
  statistics = draw_cube_with_limit(renderer, 0, paged, sizeof paged, &stats);
  CHECK(statistics.paged_geometries == 1 && statistics.paged_geometry_bytes >= 8 * 24 + 36 * 4);
  CHECK(statistics.resident_geometry_bytes == 0);
  CHECK(memcmp(in_memory, paged, sizeof paged) == 0);
  /* A load pages each geometry as it reads it: with the limit at 0, all ten of gen:fine's
   * go to the page file, and the picture is the one loading them into memory draws. */
  statistics = draw_loaded_with_limit(renderer, UINT64_MAX, in_memory, sizeof in_memory);
  CHECK(statistics.paged_geometries == 0 && statistics.resident_geometry_bytes > 0);
  statistics = draw_loaded_with_limit(renderer, 0, paged, sizeof paged);
  CHECK(statistics.paged_geometries == 10 && statistics.resident_geometry_bytes == 0);
  CHECK(statistics.visible_instances > 0);
  CHECK(memcmp(in_memory, paged, sizeof paged) == 0);
  EXPECT(cadr_scene_set_geometry_memory_limit(NULL, 0), CADR_RESULT_NULL_ARGUMENT);
  OK(cadr_renderer_destroy(renderer));
}

static void test_without_plugins(void) {
  struct CadrContextOptions options = {.size = sizeof(struct CadrContextOptions)};
  CadrContext context = NULL;
  CadrRenderer renderer = NULL;
  uint32_t count = 0;
  const char *name = NULL;
  uint64_t validation_errors = 99;

  OK(cadr_context_options_default(&options));
  options.validation = true;
  options.default_plugin_dirs = false;
  OK(cadr_context_create(&options, &context));
  OK(cadr_context_technique_count(context, &count));
  CHECK(count == 5); /* one per kind */
  OK(cadr_renderer_create(context, 32, 24, &renderer));
  OK(cadr_renderer_technique(renderer, CADR_TECHNIQUE_KIND_VERTEX, &name));
  CHECK(strcmp(name, "per-geometry") == 0);
  OK(cadr_renderer_technique(renderer, CADR_TECHNIQUE_KIND_SUBMISSION, &name));
  CHECK(strcmp(name, "individual") == 0);
  OK(cadr_renderer_destroy(renderer));
  OK(cadr_context_validation_error_count(context, &validation_errors));
  CHECK(validation_errors == 0);
  OK(cadr_context_destroy(context));
}

int main(void) {
  CadrContext context;
  struct Built built;
  uint64_t validation_errors = 99;
  char path[512];
  const char *out_dir = getenv("CADR_TEST_OUT");

  test_basics();
  test_camera();
  context = test_context();
  built = test_scene();
  test_loading(built.scene, built.root);
  test_messages(built.scene, built.root);
  test_renderer(context, &built);
  test_export(context, &built);
  test_page_file(context);
  test_without_plugins();

  /* The one-call path, with the time of each of its phases counted from a reset. */
  snprintf(path, sizeof path, "%s/one-call.png", out_dir ? out_dir : "/tmp");
  {
    struct CadrTimings timings = {.size = sizeof(struct CadrTimings)};
    cadr_timings_reset();
    OK(cadr_timings(&timings));
    CHECK(timings.device_ms == 0.0 && timings.first_frame_ms == 0.0 && timings.png_encode_ms == 0.0);
    OK(cadr_render_scene_to_png("gen:grid:parts=20", path, 32, 32, true));
    OK(cadr_timings(&timings));
    CHECK(timings.device_ms > 0.0 && timings.load_ms > 0.0 && timings.scene_build_ms > 0.0);
    CHECK(timings.upload_ms > 0.0 && timings.shader_compile_ms > 0.0);
    CHECK(timings.pipeline_creation_ms > 0.0 && timings.first_frame_ms > 0.0);
    CHECK(timings.readback_ms > 0.0 && timings.png_encode_ms > 0.0);
    EXPECT(cadr_timings(NULL), CADR_RESULT_NULL_ARGUMENT);
  }
  EXPECT(cadr_render_scene_to_png("gen:grid:parts=20", path, 0, 32, false),
         CADR_RESULT_INVALID_ARGUMENT);

  OK(cadr_context_validation_error_count(context, &validation_errors));
  CHECK(validation_errors == 0);
  EXPECT(cadr_context_validation_error_count(context, NULL), CADR_RESULT_NULL_ARGUMENT);

  {
    /* Device memory: what a renderer's targets take, and back to the figure before once it is
     * destroyed; cadr's own host memory: more with the renderer, less again without it; with
     * this header's struct, an older host's smaller one (only the fields it
     * knows are written) and a newer host's larger one (what this library does not know is
     * zeroed). */
    struct CadrMemoryUsage usage = {.size = sizeof(struct CadrMemoryUsage)};
    struct {
      struct CadrMemoryUsage usage;
      uint64_t field_of_a_later_version;
    } newer;
    uint64_t before, host_before, host_with_renderer;
    CadrRenderer memory_renderer;
    memset(&usage, 0xAB, sizeof usage);
    usage.size = sizeof usage;
    OK(cadr_context_memory_usage(context, &usage));
    CHECK(usage.size == sizeof usage && usage.device_allocated_bytes != 0xABABABABABABABABull);
    CHECK(usage.host_allocated_bytes > 0 && usage.host_allocated_bytes != 0xABABABABABABABABull);
    before = usage.device_allocated_bytes;
    host_before = usage.host_allocated_bytes;
    OK(cadr_renderer_create(context, 64, 48, &memory_renderer));
    OK(cadr_context_memory_usage(context, &usage));
    CHECK(usage.device_allocated_bytes > before);
    CHECK(usage.device_reserved_bytes >= usage.device_allocated_bytes);
    CHECK(usage.host_allocated_bytes > host_before);
    host_with_renderer = usage.host_allocated_bytes;
    memset(&usage, 0xAB, sizeof usage);
    usage.size = (uint32_t)offsetof(struct CadrMemoryUsage, device_reserved_bytes);
    OK(cadr_context_memory_usage(context, &usage));
    CHECK(usage.device_allocated_bytes > before);
    CHECK(usage.device_reserved_bytes == 0xABABABABABABABABull);
    CHECK(usage.host_allocated_bytes == 0xABABABABABABABABull);
    memset(&newer, 0xCD, sizeof newer);
    newer.usage.size = sizeof newer;
    OK(cadr_context_memory_usage(context, &newer.usage));
    CHECK(newer.usage.device_reserved_bytes >= newer.usage.device_allocated_bytes);
    CHECK(newer.field_of_a_later_version == 0 && newer.usage.size == sizeof newer);
    OK(cadr_renderer_destroy(memory_renderer));
    usage.size = sizeof usage;
    OK(cadr_context_memory_usage(context, &usage));
    CHECK(usage.device_allocated_bytes == before);
    CHECK(usage.host_allocated_bytes < host_with_renderer);
    usage.size = 2;
    EXPECT(cadr_context_memory_usage(context, &usage), CADR_RESULT_INVALID_ARGUMENT);
    MESSAGE_HAS("usage->size is 2");
    EXPECT(cadr_context_memory_usage(context, NULL), CADR_RESULT_NULL_ARGUMENT);
    EXPECT(cadr_context_memory_usage((CadrContext)built.scene, &usage),
           CADR_RESULT_FOREIGN_HANDLE);
  }

  OK(cadr_scene_destroy(built.scene));
  EXPECT(cadr_scene_destroy(built.scene), CADR_RESULT_DESTROYED_HANDLE);
  EXPECT(cadr_scene_root(built.scene, &built.root), CADR_RESULT_DESTROYED_HANDLE);
  OK(cadr_scene_destroy(NULL));
  OK(cadr_context_destroy(context));
  EXPECT(cadr_context_destroy(context), CADR_RESULT_DESTROYED_HANDLE);
  EXPECT(cadr_context_device_info(context, NULL), CADR_RESULT_DESTROYED_HANDLE);
  EXPECT(cadr_context_memory_usage(context, NULL), CADR_RESULT_DESTROYED_HANDLE);
  OK(cadr_context_destroy(NULL));
  printf("api suite: %d checks passed\n", checks);
  return 0;
}
