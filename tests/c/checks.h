/* What the C test programs (threads.c, host_vulkan.c) check cadr's calls with: OK for a call
 * that must succeed, CHECK for a condition, both exiting non-zero with the place and cadr's last
 * error message on the first failure; set_frames_in_flight; and pixel_difference to compare
 * pictures. */
#ifndef CADR_TEST_CHECKS_H
#define CADR_TEST_CHECKS_H

#include "cadr.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

/* A buffer of each thread's own where C11 has them (threads.c), one otherwise. */
#if defined(__STDC_VERSION__) && __STDC_VERSION__ >= 201112L
#define CHECKS_THREAD_LOCAL _Thread_local
#else
#define CHECKS_THREAD_LOCAL
#endif

/* cadr's last error message on this thread. */
static inline const char *last_error(void) {
  static CHECKS_THREAD_LOCAL char text[4096];
  size_t length = 0;
  if (cadr_last_error_message(text, sizeof text, &length) != CADR_RESULT_OK) {
    return "(message too long)";
  }
  return text;
}

#define OK(call)                                                                               \
  do {                                                                                         \
    enum CadrResult result_ = (call);                                                          \
    if (result_ != CADR_RESULT_OK) {                                                           \
      fprintf(stderr, "%s:%d: %s gave %s: %s\n", __FILE__, __LINE__, #call,                    \
              cadr_result_string((int32_t)result_), last_error());                            \
      exit(1);                                                                                 \
    }                                                                                          \
  } while (0)

#define CHECK(condition)                                                           \
  do {                                                                             \
    if (!(condition)) {                                                            \
      fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #condition); \
      exit(1);                                                                     \
    }                                                                              \
  } while (0)

/* Sets a renderer's frames in flight as a host does: reads its settings, changes the one,
 * applies them. */
static inline enum CadrResult set_frames_in_flight(CadrRenderer renderer, uint32_t frames) {
  CadrRendererSettings settings;
  enum CadrResult result;
  settings.size = sizeof settings;
  result = cadr_renderer_settings(renderer, &settings);
  if (result != CADR_RESULT_OK) {
    return result;
  }
  settings.frames_in_flight = frames;
  return cadr_renderer_apply_settings(renderer, &settings);
}

/* How many pixels of two RGBA8 pictures of `size` bytes differ by more than 30 in R + G + B. */
static inline unsigned pixel_difference(const uint8_t *a, const uint8_t *b, size_t size) {
  unsigned differing = 0;
  size_t i;
  for (i = 0; i < size; i += 4) {
    if (abs(a[i] - b[i]) + abs(a[i + 1] - b[i + 1]) + abs(a[i + 2] - b[i + 2]) > 30) {
      ++differing;
    }
  }
  return differing;
}

#endif
