/* cadr's frames in an OpenGL host: the memory a renderer exports its frames into
 * (cadr_renderer_create_for_export), imported as an OpenGL pixel buffer
 * (GL_EXT_memory_object_fd) and uploaded into a texture on the GPU; or, where the drivers cannot
 * share memory, frames read back through the CPU. Either way the texture is blitted into a
 * rectangle of the window. Used by gl_view.c and quad_view.c; needs a current OpenGL 3.0
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
  /* The read-back path: the frame in host memory. */
  uint8_t *pixels;
};

/* A window of `width` x `height` that does not resize, with a current OpenGL 3.0 context and
 * the functions the frames need loaded; `program` names the caller in the message when GLFW,
 * the window or the driver fails (the process then exits). */
struct GLFWwindow *gl_frames_window(const char *program, int width, int height,
                                    const char *title);

/* Whether the driver can import memory from a file descriptor (GL_EXT_memory_object_fd). */
int gl_frames_can_import(void);

/* A renderer of `width` x `height` on `context` with its way to the window: exported frames
 * where `allow_sharing` and both drivers can share memory, else an offscreen renderer read
 * back. Prints the reason when it falls back. */
void gl_frames_create(struct GlFrames *frames, CadrContext context, uint32_t width,
                      uint32_t height, int allow_sharing);

/* Whether the frames come through shared memory. */
int gl_frames_shared(const struct GlFrames *frames);

/* Puts the renderer's last frame into the window's rectangle at (x, y) (from the window's
 * top-left corner) of the frame's size, `window_height` rows tall in all. Returns the bytes
 * read back through the CPU (0 on the shared path). */
size_t gl_frames_show(struct GlFrames *frames, int x, int y, int window_height);

/* Releases the OpenGL objects and the renderer. */
void gl_frames_destroy(struct GlFrames *frames);

#endif
