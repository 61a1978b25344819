#include "sample.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void sample_check(enum CadrResult result, const char *call, const char *file, int line) {
  char message[2048];
  size_t length = 0;
  if (result == CADR_RESULT_OK) {
    return;
  }
  if (cadr_last_error_message(message, sizeof message, &length) != CADR_RESULT_OK) {
    strcpy(message, "(message too long)");
  }
  fprintf(stderr, "%s:%d: %s failed: %s: %s\n", file, line, call,
          cadr_result_string((int32_t)result), message);
  exit(1);
}

static void print_message(uint32_t severity, const char *message, void *user_data) {
  (void)user_data;
  fprintf(stderr, "cadr %s: %s\n", severity == CADR_MESSAGE_ERROR ? "error" : "warning", message);
}

void sample_print_messages(void) {
  CADR_CHECK(cadr_set_message_callback(print_message, NULL, CADR_MESSAGE_WARNING));
}

CadrContext sample_context(const char *const *extensions, uint32_t extension_count,
                           int validation) {
  struct CadrContextOptions options;
  CadrContext context;
  memset(&options, 0, sizeof options);
  options.size = sizeof options;
  CADR_CHECK(cadr_context_options_default(&options));
  options.instance_extensions = extensions;
  options.instance_extension_count = extension_count;
  options.validation = validation != 0;
  sample_print_messages();
  CADR_CHECK(cadr_context_create(&options, &context));
  return context;
}

CadrScene sample_load(const char *source, struct CadrBounds *bounds) {
  CadrScene scene;
  CadrNode root;
  struct CadrLoadResult loaded;
  CADR_CHECK(cadr_scene_create(&scene));
  CADR_CHECK(cadr_scene_root(scene, &root));
  memset(&loaded, 0, sizeof loaded);
  loaded.size = sizeof loaded;
  CADR_CHECK(cadr_scene_load(scene, source, root, &loaded));
  cadr_load_result_free(&loaded);
  CADR_CHECK(cadr_scene_bounds(scene, bounds));
  return scene;
}

void sample_set_highlighted(CadrScene scene, CadrNode node, int on) {
  uint32_t flags = 0;
  if (node == 0) {
    return;
  }
  CADR_CHECK(cadr_scene_flags(scene, node, &flags));
  flags = on ? flags | CADR_NODE_HIGHLIGHTED : flags & ~CADR_NODE_HIGHLIGHTED;
  CADR_CHECK(cadr_scene_set_flags(scene, node, flags));
}

void sample_save_offscreen(CadrContext context, CadrScene scene, const struct CadrCamera *camera,
                           uint32_t width, uint32_t height, const char *path) {
  CadrRenderer offscreen;
  CADR_CHECK(cadr_renderer_create(context, width, height, &offscreen));
  CADR_CHECK(cadr_renderer_render(offscreen, scene, camera, NULL));
  CADR_CHECK(cadr_renderer_save_png(offscreen, path));
  CADR_CHECK(cadr_renderer_destroy(offscreen));
}

void sample_screenshot_ready(uint32_t width, uint32_t height) {
  char line[64];
  printf("screenshot ready %ux%u\n", width, height);
  fflush(stdout);
  if (fgets(line, sizeof line, stdin) == NULL) {
    line[0] = '\0';
  }
}

void sample_identity(double m[16]) {
  int i;
  for (i = 0; i < 16; ++i) {
    m[i] = (i % 5 == 0) ? 1.0 : 0.0;
  }
}

void sample_translation(double m[16], double x, double y, double z) {
  sample_identity(m);
  m[12] = x;
  m[13] = y;
  m[14] = z;
}

void sample_rotate_z_translate(double m[16], double radians, double x, double y, double z) {
  sample_translation(m, x, y, z);
  m[0] = cos(radians);
  m[1] = sin(radians);
  m[4] = -sin(radians);
  m[5] = cos(radians);
}

CadrGeometry sample_box(CadrScene scene, const char *name, float hx, float hy, float hz) {
  /* 4 vertices per face so that each face has its own flat normal. */
  float positions[24 * 3], normals[24 * 3];
  uint32_t indices[36];
  struct CadrPart parts[3];
  struct CadrGeometryDesc desc = {.size = sizeof(struct CadrGeometryDesc)};
  CadrGeometry geometry;
  int face, corner, axis;
  for (face = 0; face < 6; ++face) {
    int normal_axis = face / 2, u_axis = (normal_axis + 1) % 3, v_axis = (normal_axis + 2) % 3;
    float sign = (face % 2 == 0) ? 1.0f : -1.0f, half[3];
    half[0] = hx;
    half[1] = hy;
    half[2] = hz;
    for (corner = 0; corner < 4; ++corner) {
      float u = (corner == 1 || corner == 2) ? 1.0f : -1.0f, v = (corner >= 2) ? 1.0f : -1.0f;
      float *p = positions + (face * 4 + corner) * 3, *n = normals + (face * 4 + corner) * 3;
      for (axis = 0; axis < 3; ++axis) {
        n[axis] = 0.0f;
      }
      n[normal_axis] = sign;
      p[normal_axis] = sign * half[normal_axis];
      p[u_axis] = u * half[u_axis] * sign;
      p[v_axis] = v * half[v_axis];
    }
    {
      uint32_t base = (uint32_t)face * 4, *t = indices + face * 6;
      t[0] = base;
      t[1] = base + 1;
      t[2] = base + 2;
      t[3] = base;
      t[4] = base + 2;
      t[5] = base + 3;
    }
  }
  for (axis = 0; axis < 3; ++axis) {
    parts[axis].first_index = (uint32_t)axis * 12;
    parts[axis].index_count = 12;
    parts[axis].first_wire_index = 0;
    parts[axis].wire_index_count = 0;
  }
  memset(&desc, 0, sizeof desc);
  desc.size = sizeof desc;
  desc.name = name;
  desc.positions = positions;
  desc.normals = normals;
  desc.vertex_count = 24;
  desc.indices = indices;
  desc.index_count = 36;
  desc.parts = parts;
  desc.part_count = 3;
  CADR_CHECK(cadr_scene_create_geometry(scene, &desc, &geometry));
  return geometry;
}

CadrGeometry sample_cylinder(CadrScene scene, const char *name, float radius, float height,
                             int segments) {
  /* Side: 2 rings with outward normals; caps: a centre and a ring each, with axial normals. */
  int n = segments, i;
  uint32_t vertex_count = (uint32_t)(4 * n + 2);
  float *positions = (float *)malloc(sizeof(float) * 3 * vertex_count);
  float *normals = (float *)malloc(sizeof(float) * 3 * vertex_count);
  uint32_t *indices = (uint32_t *)malloc(sizeof(uint32_t) * (size_t)(12 * n));
  uint32_t index = 0, top_centre = (uint32_t)(4 * n), bottom_centre = top_centre + 1;
  struct CadrPart parts[2];
  struct CadrGeometryDesc desc = {.size = sizeof(struct CadrGeometryDesc)};
  CadrGeometry geometry;
  if (positions == NULL || normals == NULL || indices == NULL) {
    fprintf(stderr, "out of memory\n");
    exit(1);
  }
  for (i = 0; i < n; ++i) {
    float angle = 6.2831853f * (float)i / (float)n, c = cosf(angle), s = sinf(angle);
    float ring[4][6];
    int k, j;
    /* side bottom, side top, cap top, cap bottom */
    float zs[4] = {0.0f, height, height, 0.0f};
    for (k = 0; k < 4; ++k) {
      ring[k][0] = radius * c;
      ring[k][1] = radius * s;
      ring[k][2] = zs[k];
      ring[k][3] = k < 2 ? c : 0.0f;
      ring[k][4] = k < 2 ? s : 0.0f;
      ring[k][5] = k < 2 ? 0.0f : (k == 2 ? 1.0f : -1.0f);
      for (j = 0; j < 3; ++j) {
        positions[(k * n + i) * 3 + j] = ring[k][j];
        normals[(k * n + i) * 3 + j] = ring[k][3 + j];
      }
    }
  }
  for (i = 0; i < 3; ++i) {
    positions[top_centre * 3 + (uint32_t)i] = (i == 2) ? height : 0.0f;
    positions[bottom_centre * 3 + (uint32_t)i] = 0.0f;
    normals[top_centre * 3 + (uint32_t)i] = (i == 2) ? 1.0f : 0.0f;
    normals[bottom_centre * 3 + (uint32_t)i] = (i == 2) ? -1.0f : 0.0f;
  }
  for (i = 0; i < n; ++i) {
    uint32_t a = (uint32_t)i, b = (uint32_t)((i + 1) % n), un = (uint32_t)n;
    indices[index++] = a;
    indices[index++] = b;
    indices[index++] = un + b;
    indices[index++] = a;
    indices[index++] = un + b;
    indices[index++] = un + a;
  }
  for (i = 0; i < n; ++i) {
    uint32_t a = (uint32_t)i, b = (uint32_t)((i + 1) % n), un = (uint32_t)n;
    indices[index++] = top_centre;
    indices[index++] = 2 * un + a;
    indices[index++] = 2 * un + b;
    indices[index++] = bottom_centre;
    indices[index++] = 3 * un + b;
    indices[index++] = 3 * un + a;
  }
  parts[0].first_index = 0;
  parts[0].index_count = (uint32_t)(6 * n);
  parts[1].first_index = (uint32_t)(6 * n);
  parts[1].index_count = (uint32_t)(6 * n);
  parts[0].first_wire_index = parts[1].first_wire_index = 0;
  parts[0].wire_index_count = parts[1].wire_index_count = 0;
  memset(&desc, 0, sizeof desc);
  desc.size = sizeof desc;
  desc.name = name;
  desc.positions = positions;
  desc.normals = normals;
  desc.vertex_count = vertex_count;
  desc.indices = indices;
  desc.index_count = index;
  desc.parts = parts;
  desc.part_count = 2;
  CADR_CHECK(cadr_scene_create_geometry(scene, &desc, &geometry));
  free(positions);
  free(normals);
  free(indices);
  return geometry;
}

CadrMaterial sample_material(CadrScene scene, const char *name, float r, float g, float b,
                             float metallic, float roughness) {
  struct CadrMaterialDesc desc = {.size = sizeof(struct CadrMaterialDesc)};
  CadrMaterial material;
  desc.name = name;
  desc.base_color[0] = r;
  desc.base_color[1] = g;
  desc.base_color[2] = b;
  desc.base_color[3] = 1.0f;
  desc.metallic = metallic;
  desc.roughness = roughness;
  CADR_CHECK(cadr_scene_create_material(scene, &desc, &material));
  return material;
}
