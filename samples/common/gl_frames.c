/* cadr's frames in an OpenGL host: see gl_frames.h. */
#define _POSIX_C_SOURCE 200809L
#define GLFW_INCLUDE_GLEXT
#include <GLFW/glfw3.h>

#include "common/gl_frames.h"
#include "common/sample.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* The OpenGL functions beyond 1.1, loaded through GLFW. */
static struct {
  PFNGLGENBUFFERSPROC GenBuffers;
  PFNGLBINDBUFFERPROC BindBuffer;
  PFNGLDELETEBUFFERSPROC DeleteBuffers;
  PFNGLGENFRAMEBUFFERSPROC GenFramebuffers;
  PFNGLBINDFRAMEBUFFERPROC BindFramebuffer;
  PFNGLFRAMEBUFFERTEXTURE2DPROC FramebufferTexture2D;
  PFNGLBLITFRAMEBUFFERPROC BlitFramebuffer;
  PFNGLDELETEFRAMEBUFFERSPROC DeleteFramebuffers;
  PFNGLTEXSTORAGE2DPROC TexStorage2D;
  PFNGLGETBUFFERSUBDATAPROC GetBufferSubData;
  /* GL_EXT_memory_object(_fd); NULL where the driver lacks them. */
  PFNGLCREATEMEMORYOBJECTSEXTPROC CreateMemoryObjectsEXT;
  PFNGLDELETEMEMORYOBJECTSEXTPROC DeleteMemoryObjectsEXT;
  PFNGLIMPORTMEMORYFDEXTPROC ImportMemoryFdEXT;
  PFNGLBUFFERSTORAGEMEMEXTPROC BufferStorageMemEXT;
  PFNGLGETUNSIGNEDBYTEVEXTPROC GetUnsignedBytevEXT;
  PFNGLGETUNSIGNEDBYTEI_VEXTPROC GetUnsignedBytei_vEXT;
  /* GL_EXT_semaphore(_fd); NULL where the driver lacks them. */
  PFNGLGENSEMAPHORESEXTPROC GenSemaphoresEXT;
  PFNGLDELETESEMAPHORESEXTPROC DeleteSemaphoresEXT;
  PFNGLIMPORTSEMAPHOREFDEXTPROC ImportSemaphoreFdEXT;
  PFNGLWAITSEMAPHOREEXTPROC WaitSemaphoreEXT;
  PFNGLSIGNALSEMAPHOREEXTPROC SignalSemaphoreEXT;
} gl;

#define LOAD(name, type) (gl.name = (type)glfwGetProcAddress("gl" #name))

/* Loads the OpenGL functions the frames need; 0 when the driver lacks framebuffer blits or
 * texture storage. */
static int load_functions(void) {
  LOAD(GenBuffers, PFNGLGENBUFFERSPROC);
  LOAD(BindBuffer, PFNGLBINDBUFFERPROC);
  LOAD(DeleteBuffers, PFNGLDELETEBUFFERSPROC);
  LOAD(GenFramebuffers, PFNGLGENFRAMEBUFFERSPROC);
  LOAD(BindFramebuffer, PFNGLBINDFRAMEBUFFERPROC);
  LOAD(FramebufferTexture2D, PFNGLFRAMEBUFFERTEXTURE2DPROC);
  LOAD(BlitFramebuffer, PFNGLBLITFRAMEBUFFERPROC);
  LOAD(DeleteFramebuffers, PFNGLDELETEFRAMEBUFFERSPROC);
  LOAD(TexStorage2D, PFNGLTEXSTORAGE2DPROC);
  LOAD(GetBufferSubData, PFNGLGETBUFFERSUBDATAPROC);
  if (glfwExtensionSupported("GL_EXT_memory_object") &&
      glfwExtensionSupported("GL_EXT_memory_object_fd")) {
    LOAD(CreateMemoryObjectsEXT, PFNGLCREATEMEMORYOBJECTSEXTPROC);
    LOAD(DeleteMemoryObjectsEXT, PFNGLDELETEMEMORYOBJECTSEXTPROC);
    LOAD(ImportMemoryFdEXT, PFNGLIMPORTMEMORYFDEXTPROC);
    LOAD(BufferStorageMemEXT, PFNGLBUFFERSTORAGEMEMEXTPROC);
    LOAD(GetUnsignedBytevEXT, PFNGLGETUNSIGNEDBYTEVEXTPROC);
    LOAD(GetUnsignedBytei_vEXT, PFNGLGETUNSIGNEDBYTEI_VEXTPROC);
  }
  if (glfwExtensionSupported("GL_EXT_semaphore") &&
      glfwExtensionSupported("GL_EXT_semaphore_fd")) {
    LOAD(GenSemaphoresEXT, PFNGLGENSEMAPHORESEXTPROC);
    LOAD(DeleteSemaphoresEXT, PFNGLDELETESEMAPHORESEXTPROC);
    LOAD(ImportSemaphoreFdEXT, PFNGLIMPORTSEMAPHOREFDEXTPROC);
    LOAD(WaitSemaphoreEXT, PFNGLWAITSEMAPHOREEXTPROC);
    LOAD(SignalSemaphoreEXT, PFNGLSIGNALSEMAPHOREEXTPROC);
  }
  return gl.GenBuffers && gl.BindBuffer && gl.DeleteBuffers && gl.GenFramebuffers &&
         gl.BindFramebuffer && gl.FramebufferTexture2D && gl.BlitFramebuffer &&
         gl.DeleteFramebuffers && gl.TexStorage2D && gl.GetBufferSubData;
}

GLFWwindow *gl_frames_window(const char *program, int width, int height, const char *title) {
  GLFWwindow *window;
  if (!glfwInit()) {
    fprintf(stderr, "%s: GLFW could not start (no display?)\n", program);
    exit(1);
  }
  glfwWindowHint(GLFW_CLIENT_API, GLFW_OPENGL_API);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 0);
  glfwWindowHint(GLFW_RESIZABLE, GLFW_FALSE);
  window = glfwCreateWindow(width, height, title, NULL, NULL);
  if (window == NULL) {
    fprintf(stderr, "%s: no OpenGL 3.0 window\n", program);
    exit(1);
  }
  glfwMakeContextCurrent(window);
  if (!load_functions()) {
    fprintf(stderr, "%s: the OpenGL driver lacks framebuffer blits or texture storage\n",
            program);
    exit(1);
  }
  printf("OpenGL: %s, %s\n", (const char *)glGetString(GL_VERSION),
         (const char *)glGetString(GL_RENDERER));
  return window;
}

int gl_frames_can_import(void) {
  return gl.ImportMemoryFdEXT != NULL && gl.CreateMemoryObjectsEXT != NULL &&
         gl.BufferStorageMemEXT != NULL && gl.DeleteMemoryObjectsEXT != NULL &&
         gl.GetUnsignedBytevEXT != NULL && gl.GetUnsignedBytei_vEXT != NULL;
}

/* Whether the OpenGL driver is the one cadr's memory comes from: the same driver UUID and one
 * of its devices with the same device UUID (what GL_EXT_external_objects asks an importer to
 * check). */
static int same_device(const CadrExportedFrame *exported) {
  GLubyte driver[GL_UUID_SIZE_EXT], device[GL_UUID_SIZE_EXT];
  GLint devices = 0, i;
  gl.GetUnsignedBytevEXT(GL_DRIVER_UUID_EXT, driver);
  if (memcmp(driver, exported->driver_uuid, GL_UUID_SIZE_EXT) != 0) {
    return 0;
  }
  glGetIntegerv(GL_NUM_DEVICE_UUIDS_EXT, &devices);
  for (i = 0; i < devices; ++i) {
    gl.GetUnsignedBytei_vEXT(GL_DEVICE_UUID_EXT, (GLuint)i, device);
    if (memcmp(device, exported->device_uuid, GL_UUID_SIZE_EXT) == 0) {
      return 1;
    }
  }
  return 0;
}

/* Imports the renderer's exported memory as a pixel buffer; 0 when the driver refuses it. A
 * host whose view resizes calls it again after cadr_renderer_resize (the frames then go to new
 * memory, of a new generation). */
static int import_frames(struct GlFrames *frames) {
  CadrExportedFrame exported;
  memset(&exported, 0, sizeof exported);
  exported.size = sizeof exported;
  CADR_CHECK(cadr_renderer_exported_frame(frames->renderer, &exported));
  if (!same_device(&exported)) {
    close(exported.fd);
    printf("the OpenGL driver is not the one cadr renders with (their UUIDs differ)\n");
    return 0;
  }
  while (glGetError() != GL_NO_ERROR) {
    /* Earlier errors are not the import's. */
  }
  gl.CreateMemoryObjectsEXT(1, &frames->memory_object);
  /* The import takes the file descriptor. */
  gl.ImportMemoryFdEXT(frames->memory_object, exported.allocation_size,
                       GL_HANDLE_TYPE_OPAQUE_FD_EXT, exported.fd);
  gl.GenBuffers(1, &frames->pixel_buffer);
  gl.BindBuffer(GL_PIXEL_UNPACK_BUFFER, frames->pixel_buffer);
  /* The colour, and the depth after it where the renderer exports it. */
  frames->depth_offset = exported.depth_offset;
  gl.BufferStorageMemEXT(GL_PIXEL_UNPACK_BUFFER,
                         exported.depth_offset != 0
                             ? (GLsizeiptr)(exported.depth_offset +
                                            (uint64_t)exported.depth_row_bytes * exported.height)
                             : (GLsizeiptr)exported.row_bytes * exported.height,
                         frames->memory_object, 0);
  gl.BindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
  if (glGetError() != GL_NO_ERROR) {
    gl.DeleteBuffers(1, &frames->pixel_buffer);
    gl.DeleteMemoryObjectsEXT(1, &frames->memory_object);
    frames->memory_object = 0;
    frames->pixel_buffer = 0;
    return 0;
  }
  return 1;
}

/* Hands the frames over by the renderer's two semaphores, imported into OpenGL, where both
 * drivers can share them: each update then waits for cadr's copy on the GPU instead of cadr
 * waiting for it on the CPU. Says which way the frames come. */
static void import_semaphores(struct GlFrames *frames) {
  CadrExportedSemaphores semaphores;
  if (gl.GenSemaphoresEXT == NULL || gl.DeleteSemaphoresEXT == NULL ||
      gl.ImportSemaphoreFdEXT == NULL || gl.WaitSemaphoreEXT == NULL ||
      gl.SignalSemaphoreEXT == NULL) {
    printf("no shared semaphores (no GL_EXT_semaphore_fd): cadr waits for each frame's copy\n");
    return;
  }
  memset(&semaphores, 0, sizeof semaphores);
  semaphores.size = sizeof semaphores;
  if (cadr_renderer_export_semaphores(frames->renderer, &semaphores) != CADR_RESULT_OK) {
    printf("no shared semaphores (cadr cannot export them on this device): cadr waits for each "
           "frame's copy\n");
    return;
  }
  gl.GenSemaphoresEXT(1, &frames->ready_semaphore);
  gl.GenSemaphoresEXT(1, &frames->released_semaphore);
  /* The imports take the file descriptors. */
  gl.ImportSemaphoreFdEXT(frames->ready_semaphore, GL_HANDLE_TYPE_OPAQUE_FD_EXT,
                          semaphores.ready_fd);
  gl.ImportSemaphoreFdEXT(frames->released_semaphore, GL_HANDLE_TYPE_OPAQUE_FD_EXT,
                          semaphores.released_fd);
  printf("frames handed over by semaphores\n");
}

/* Asks the renderer to keep each frame's depth for the host (exported after the colour, or
 * read back). */
static void depth_to_host(CadrRenderer renderer) {
  struct CadrRendererSettings settings;
  memset(&settings, 0, sizeof settings);
  settings.size = sizeof settings;
  CADR_CHECK(cadr_renderer_settings(renderer, &settings));
  settings.depth_to_host = true;
  CADR_CHECK(cadr_renderer_apply_settings(renderer, &settings));
}

/* A depth texture of the frames' size beside the colour in their framebuffer. */
static void attach_depth(struct GlFrames *frames) {
  glGenTextures(1, &frames->depth_texture);
  glBindTexture(GL_TEXTURE_2D, frames->depth_texture);
  gl.TexStorage2D(GL_TEXTURE_2D, 1, GL_DEPTH_COMPONENT32F, (GLsizei)frames->width,
                  (GLsizei)frames->height);
  gl.BindFramebuffer(GL_READ_FRAMEBUFFER, frames->framebuffer);
  gl.FramebufferTexture2D(GL_READ_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D,
                          frames->depth_texture, 0);
  gl.BindFramebuffer(GL_READ_FRAMEBUFFER, 0);
}

void gl_frames_create(struct GlFrames *frames, CadrContext context, uint32_t width,
                      uint32_t height, int flags) {
  const int allow_sharing = (flags & GL_FRAMES_SHARE) != 0;
  memset(frames, 0, sizeof *frames);
  frames->width = width;
  frames->height = height;
  glGenTextures(1, &frames->texture);
  glBindTexture(GL_TEXTURE_2D, frames->texture);
  gl.TexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA8, (GLsizei)width, (GLsizei)height);
  gl.GenFramebuffers(1, &frames->framebuffer);
  gl.BindFramebuffer(GL_READ_FRAMEBUFFER, frames->framebuffer);
  gl.FramebufferTexture2D(GL_READ_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D,
                          frames->texture, 0);
  gl.BindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  if (allow_sharing && !gl_frames_can_import()) {
    printf("shared memory unavailable (no GL_EXT_memory_object_fd): reading frames back\n");
  } else if (allow_sharing) {
    if (cadr_renderer_create_for_export(context, width, height, &frames->renderer) !=
        CADR_RESULT_OK) {
      printf("shared memory unavailable (cadr cannot export frames on this device): reading "
             "frames back\n");
      frames->renderer = NULL;
    } else {
      if (flags & GL_FRAMES_DEPTH) {
        depth_to_host(frames->renderer);
      }
      if (!import_frames(frames)) {
        printf("the OpenGL driver refused cadr's memory: reading frames back\n");
        CADR_CHECK(cadr_renderer_destroy(frames->renderer));
        frames->renderer = NULL;
      } else {
        import_semaphores(frames);
      }
    }
  }
  if (frames->renderer == NULL) {
    CADR_CHECK(cadr_renderer_create(context, width, height, &frames->renderer));
    frames->pixels = (uint8_t *)malloc((size_t)width * height * 4);
    if (frames->pixels == NULL) {
      fprintf(stderr, "out of memory\n");
      exit(1);
    }
    if (flags & GL_FRAMES_DEPTH) {
      depth_to_host(frames->renderer);
      frames->depth_values = (float *)malloc((size_t)width * height * sizeof(float));
      if (frames->depth_values == NULL) {
        fprintf(stderr, "out of memory\n");
        exit(1);
      }
    }
  }
  if (frames->depth_offset != 0 || frames->depth_values != NULL) {
    attach_depth(frames);
  }
}

int gl_frames_shared(const struct GlFrames *frames) {
  return frames->pixel_buffer != 0;
}

int gl_frames_has_depth(const struct GlFrames *frames) {
  return frames->depth_texture != 0;
}

void gl_frames_render(struct GlFrames *frames, CadrScene scene, const CadrCamera *camera,
                      CadrFrameStats *stats) {
  if (frames->frame_pending && frames->ready_semaphore != 0) {
    gl_frames_update(frames); /* its semaphores must be spent before the next frame's */
  }
  CADR_CHECK(cadr_renderer_render(frames->renderer, scene, camera, stats));
  frames->frame_pending = 1;
}

size_t gl_frames_update(struct GlFrames *frames) {
  size_t read_back = 0;
  const GLsizei width = (GLsizei)frames->width, height = (GLsizei)frames->height;
  if (frames->ready_semaphore != 0 && !frames->frame_pending) {
    return 0; /* the textures hold the last frame; its semaphores are spent */
  }
  frames->frame_pending = 0;
  glBindTexture(GL_TEXTURE_2D, frames->texture);
  if (frames->pixel_buffer != 0) {
    /* From the shared memory to the textures, on the GPU: after cadr's copy where the frames
     * come by semaphores, releasing the memory to cadr's next copy after the uploads. */
    if (frames->ready_semaphore != 0) {
      gl.WaitSemaphoreEXT(frames->ready_semaphore, 1, &frames->pixel_buffer, 0, NULL, NULL);
    }
    gl.BindBuffer(GL_PIXEL_UNPACK_BUFFER, frames->pixel_buffer);
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, NULL);
    if (frames->depth_texture != 0) {
      glBindTexture(GL_TEXTURE_2D, frames->depth_texture);
      glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width, height, GL_DEPTH_COMPONENT, GL_FLOAT,
                      (const void *)(uintptr_t)frames->depth_offset);
    }
    gl.BindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
    if (frames->released_semaphore != 0) {
      gl.SignalSemaphoreEXT(frames->released_semaphore, 1, &frames->pixel_buffer, 0, NULL, NULL);
      glFlush(); /* cadr's next copy waits for the signal: it must reach the GPU first */
    }
  } else {
    const size_t bytes = (size_t)width * height * 4;
    read_back = bytes;
    CADR_CHECK(cadr_renderer_read_pixels(frames->renderer, frames->pixels, bytes));
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE,
                    frames->pixels);
    if (frames->depth_values != NULL) {
      read_back += bytes;
      CADR_CHECK(cadr_renderer_read_depth(frames->renderer, frames->depth_values, bytes));
      glBindTexture(GL_TEXTURE_2D, frames->depth_texture);
      glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, width, height, GL_DEPTH_COMPONENT, GL_FLOAT,
                      frames->depth_values);
    }
  }
  return read_back;
}

void gl_frames_read_depth(struct GlFrames *frames, float *depth) {
  const size_t bytes = (size_t)frames->width * frames->height * 4;
  if (frames->depth_values != NULL) {
    memcpy(depth, frames->depth_values, bytes);
    return;
  }
  gl.BindBuffer(GL_PIXEL_UNPACK_BUFFER, frames->pixel_buffer);
  gl.GetBufferSubData(GL_PIXEL_UNPACK_BUFFER, (GLintptr)frames->depth_offset,
                      (GLsizeiptr)bytes, depth);
  gl.BindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
}

void gl_frames_begin_drawing(struct GlFrames *frames) {
  gl.BindFramebuffer(GL_FRAMEBUFFER, frames->framebuffer);
  glViewport(0, 0, (GLsizei)frames->width, (GLsizei)frames->height);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
}

void gl_frames_load_camera(const CadrCamera *camera) {
  /* Vulkan's clip depth is z/w in 0..1, OpenGL's (z/w + 1) / 2 from -1..1: z' = 2z - w makes
   * OpenGL's window depth the frame's. */
  double projection[16];
  int column;
  for (column = 0; column < 4; ++column) {
    const double *from = &camera->projection[column * 4];
    double *to = &projection[column * 4];
    to[0] = from[0];
    to[1] = from[1];
    to[2] = 2.0 * from[2] - from[3];
    to[3] = from[3];
  }
  glMatrixMode(GL_PROJECTION);
  glLoadMatrixd(projection);
  glMatrixMode(GL_MODELVIEW);
  glLoadMatrixd(camera->view);
}

void gl_frames_end_drawing(void) {
  glDisable(GL_DEPTH_TEST);
  gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
}

void gl_frames_blit(struct GlFrames *frames, int x, int y, int window_height) {
  const GLsizei width = (GLsizei)frames->width, height = (GLsizei)frames->height;
  const GLint bottom = window_height - y - height;
  /* Row 0 of a frame is its top row: blit it to the rectangle's top (GL counts rows up). */
  gl.BindFramebuffer(GL_READ_FRAMEBUFFER, frames->framebuffer);
  gl.BindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  gl.BlitFramebuffer(0, 0, width, height, x, bottom + height, x + width, bottom,
                     GL_COLOR_BUFFER_BIT, GL_NEAREST);
  gl.BindFramebuffer(GL_READ_FRAMEBUFFER, 0);
}

size_t gl_frames_show(struct GlFrames *frames, int x, int y, int window_height) {
  const size_t read_back = gl_frames_update(frames);
  gl_frames_blit(frames, x, y, window_height);
  return read_back;
}

void gl_frames_destroy(struct GlFrames *frames) {
  if (frames->pixel_buffer != 0) {
    gl.DeleteBuffers(1, &frames->pixel_buffer);
    gl.DeleteMemoryObjectsEXT(1, &frames->memory_object);
  }
  if (frames->ready_semaphore != 0) {
    gl.DeleteSemaphoresEXT(1, &frames->ready_semaphore);
    gl.DeleteSemaphoresEXT(1, &frames->released_semaphore);
  }
  gl.DeleteFramebuffers(1, &frames->framebuffer);
  glDeleteTextures(1, &frames->texture);
  if (frames->depth_texture != 0) {
    glDeleteTextures(1, &frames->depth_texture);
  }
  free(frames->pixels);
  free(frames->depth_values);
  if (frames->renderer != NULL) {
    CADR_CHECK(cadr_renderer_destroy(frames->renderer));
  }
  memset(frames, 0, sizeof *frames);
}
