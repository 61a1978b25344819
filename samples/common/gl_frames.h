/* cadr's frames in an OpenGL host: the memory a renderer exports its frames into
 * (cadr_renderer_create_for_export), imported as an OpenGL pixel buffer
 * (GL_EXT_memory_object_fd) and uploaded into a texture on the GPU; or, where the drivers cannot
 * share memory, frames read back through the CPU. Where both drivers share semaphores too
 * (GL_EXT_semaphore_fd), the frames are handed over by them (cadr_renderer_export_semaphores),
 * so that neither side waits for the other on the CPU. Either way the texture is blitted into a
 * rectangle of the window. With the frames' depth (exported after the colour,
 * CadrRendererSettings::depth_to_host), the host draws its own geometry into cadr's frame with
 * a depth test before the blit. Used by gl_view.c and quad_view.c; needs a current OpenGL 3.0
 * context (GLFW's). */
#ifndef CADR_SAMPLE_GL_FRAMES_H
#define CADR_SAMPLE_GL_FRAMES_H

#include <stddef.h>
#include <stdint.h>

#include "cadr.h"

/* The frames of one renderer on their way to the window. */
struct GlFrames {
  CadrRenderer renderer;
  uint32_t width, height;
  unsigned texture, framebuffer;
  /* The shared path: the exported memory as a buffer (0 on the read-back path). */
  unsigned memory_object, pixel_buffer;
  /* Where both drivers share semaphores: cadr's `ready` and the host's `released`, imported
   * (0 when cadr waits for each frame's copy instead). */
  unsigned ready_semaphore, released_semaphore;
  /* Whether the renderer has rendered a frame that gl_frames_update has not brought in yet:
   * with semaphores, each frame is waited for and released exactly once. */
  int frame_pending;
  /* With depth: the depth texture beside the colour in the framebuffer, and where the depth
   * starts in the exported memory (0 without depth). */
  unsigned depth_texture;
  uint64_t depth_offset;
  /* The read-back path: the frame in host memory (and its depth, with depth). */
  uint8_t *pixels;
  float *depth_values;
};

/* A window of `width` x `height` that does not resize, with a current OpenGL 3.0 context and
 * the functions the frames need loaded; `program` names the caller in the message when GLFW,
 * the window or the driver fails (the process then exits). */
struct GLFWwindow *gl_frames_window(const char *program, int width, int height,
                                    const char *title);

/* Whether the driver can import memory from a file descriptor (GL_EXT_memory_object_fd). */
int gl_frames_can_import(void);

/* What gl_frames_create is asked for. */
enum {
  /* Frames through shared memory where both drivers allow it (else read back). */
  GL_FRAMES_SHARE = 1,
  /* The frames' depth too, for gl_frames_begin_drawing. */
  GL_FRAMES_DEPTH = 2
};

/* A renderer of `width` x `height` on `context` with its way to the window: exported frames
 * where `flags` has GL_FRAMES_SHARE and both drivers can share memory, else an offscreen
 * renderer read back; with GL_FRAMES_DEPTH, the exported frames bring their depth. Prints the
 * reason when it falls back. */
void gl_frames_create(struct GlFrames *frames, CadrContext context, uint32_t width,
                      uint32_t height, int flags);

/* Whether the frames come through shared memory. */
int gl_frames_shared(const struct GlFrames *frames);

/* Whether the frames bring their depth (GL_FRAMES_DEPTH). */
int gl_frames_has_depth(const struct GlFrames *frames);

/* Renders a frame of `scene` from `camera` (cadr_renderer_render, `stats` may be NULL) for
 * gl_frames_update to bring in. With semaphores, a frame rendered before and never brought in
 * is brought in first: each frame must be waited for and released before the next. */
void gl_frames_render(struct GlFrames *frames, CadrScene scene, const CadrCamera *camera,
                      CadrFrameStats *stats);

/* Brings the renderer's last frame (and its depth) into the frames' textures. Called again
 * for the same frame, it brings nothing on the semaphore path (the textures hold it already).
 * Returns the bytes read back through the CPU (0 on the shared path). */
size_t gl_frames_update(struct GlFrames *frames);

/* The last frame's depth (width x height floats, the top row first) in host memory: read
 * from the shared memory through the CPU, for checks, not for drawing. Only with depth. */
void gl_frames_read_depth(struct GlFrames *frames, float *depth);

/* Makes the frames' framebuffer (the last frame's colour, and its depth) the target of the
 * host's drawing, with the viewport over it and the depth test on: geometry drawn with cadr's
 * camera (gl_frames_load_camera) is hidden where cadr's parts are in front of it. */
void gl_frames_begin_drawing(struct GlFrames *frames);

/* Loads `camera` (cadr's Vulkan-style matrices) as OpenGL's projection and model-view
 * matrices, adjusted so that OpenGL's depth matches the frame's (0 near, 1 far). */
void gl_frames_load_camera(const CadrCamera *camera);

/* Ends the host's drawing into the frames' framebuffer. */
void gl_frames_end_drawing(void);

/* Blits the frames' colour texture into the window's rectangle at (x, y) (from the window's
 * top-left corner) of the frame's size, `window_height` rows tall in all. */
void gl_frames_blit(struct GlFrames *frames, int x, int y, int window_height);

/* gl_frames_update and gl_frames_blit; returns the bytes read back. */
size_t gl_frames_show(struct GlFrames *frames, int x, int y, int window_height);

/* Releases the OpenGL objects and the renderer. */
void gl_frames_destroy(struct GlFrames *frames);

#endif
