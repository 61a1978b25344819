/* An OpenGL host's hand-over of exported frames by semaphores
 * (cadr_renderer_export_semaphores), played by a second Vulkan device of the same driver, as
 * OpenGL would play it: it imports the exported memory and both semaphores once, and for every
 * frame waits for `ready`, copies the frame out of the memory and signals `released`. The
 * frames it reads must be the renderer's own (cadr_renderer_read_pixels), frame after frame and
 * across a resize, with no validation error on cadr's side. A host that does not release a
 * frame gets an error naming `released` from the render after next, and goes on once it has
 * released it.
 *
 * Where the driver cannot export semaphores as file descriptors (lavapipe), the call must be
 * refused naming what is missing, and the driver must indeed lack VK_KHR_external_semaphore_fd;
 * the program then says "semaphores unsupported".
 *
 * Built by tests/tests/c_api.rs with the strict flags and -lvulkan; run there on lavapipe and on
 * SwiftShader. Exits non-zero on the first failed check. */
#define _POSIX_C_SOURCE 200809L
#include "cadr.h"
#include "checks.h"
#include "vulkan_checks.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <vulkan/vulkan.h>

enum { W = 96, H = 72, W2 = 80, H2 = 64, FRAMES = 3 };

/* How long the importer waits for a copy of its own, in nanoseconds: far beyond a frame. */
static const uint64_t IMPORTER_TIMEOUT = 20ull * 1000 * 1000 * 1000;

/* The importing side: its own instance and device of the same driver. */
struct Importer {
  VkInstance instance;
  VkPhysicalDevice physical;
  VkDevice device;
  VkQueue queue;
  PFN_vkImportSemaphoreFdKHR import_semaphore_fd;
  VkSemaphore ready, released;
  VkCommandPool pool;
  VkCommandBuffer copy;
  VkFence fence;
};

/* The exported memory as the importer holds it, with a readable buffer to copy frames into. */
struct Imported {
  VkBuffer shared, readable;
  VkDeviceMemory shared_memory, readable_memory;
  const uint8_t *pixels;
  uint64_t generation;
  uint32_t width, height;
};

static int has_extension(VkPhysicalDevice physical, const char *name) {
  VkExtensionProperties extensions[512];
  uint32_t count = 512, i;
  VkResult result = vkEnumerateDeviceExtensionProperties(physical, NULL, &count, extensions);
  CHECK(result == VK_SUCCESS || result == VK_INCOMPLETE);
  for (i = 0; i < count; ++i) {
    if (strcmp(extensions[i].extensionName, name) == 0) {
      return 1;
    }
  }
  return 0;
}

/* The instance, and the physical device whose UUID is the exported one's. */
static void importer_find_device(struct Importer *im, const uint8_t device_uuid[16]) {
  VkApplicationInfo app;
  VkInstanceCreateInfo instance_info;
  VkPhysicalDevice physicals[8];
  uint32_t count = 8, i;
  memset(im, 0, sizeof *im);
  memset(&app, 0, sizeof app);
  app.sType = VK_STRUCTURE_TYPE_APPLICATION_INFO;
  app.pApplicationName = "cadr export importer";
  app.apiVersion = VK_API_VERSION_1_3;
  memset(&instance_info, 0, sizeof instance_info);
  instance_info.sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO;
  instance_info.pApplicationInfo = &app;
  VK_OK(vkCreateInstance(&instance_info, NULL, &im->instance));
  VK_OK(vkEnumeratePhysicalDevices(im->instance, &count, physicals));
  for (i = 0; i < count; ++i) {
    VkPhysicalDeviceIDProperties ids;
    VkPhysicalDeviceProperties2 properties;
    memset(&ids, 0, sizeof ids);
    ids.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ID_PROPERTIES;
    memset(&properties, 0, sizeof properties);
    properties.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2;
    properties.pNext = &ids;
    vkGetPhysicalDeviceProperties2(physicals[i], &properties);
    if (memcmp(ids.deviceUUID, device_uuid, VK_UUID_SIZE) == 0) {
      im->physical = physicals[i];
    }
  }
  CHECK(im->physical != VK_NULL_HANDLE);
}

/* The device (queue family 0, which copies on both drivers), its copy commands and fence. */
static void importer_create_device(struct Importer *im) {
  const char *extensions[2] = {"VK_KHR_external_memory_fd", "VK_KHR_external_semaphore_fd"};
  float priority = 1.0f;
  VkDeviceQueueCreateInfo queue_info;
  VkDeviceCreateInfo device_info;
  VkCommandPoolCreateInfo pool_info;
  VkCommandBufferAllocateInfo allocation;
  VkFenceCreateInfo fence_info;
  memset(&queue_info, 0, sizeof queue_info);
  queue_info.sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO;
  queue_info.queueCount = 1;
  queue_info.pQueuePriorities = &priority;
  memset(&device_info, 0, sizeof device_info);
  device_info.sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO;
  device_info.queueCreateInfoCount = 1;
  device_info.pQueueCreateInfos = &queue_info;
  device_info.enabledExtensionCount = 2;
  device_info.ppEnabledExtensionNames = extensions;
  VK_OK(vkCreateDevice(im->physical, &device_info, NULL, &im->device));
  vkGetDeviceQueue(im->device, 0, 0, &im->queue);
  im->import_semaphore_fd =
      (PFN_vkImportSemaphoreFdKHR)vkGetDeviceProcAddr(im->device, "vkImportSemaphoreFdKHR");
  CHECK(im->import_semaphore_fd != NULL);
  memset(&pool_info, 0, sizeof pool_info);
  pool_info.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO;
  pool_info.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  VK_OK(vkCreateCommandPool(im->device, &pool_info, NULL, &im->pool));
  memset(&allocation, 0, sizeof allocation);
  allocation.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO;
  allocation.commandPool = im->pool;
  allocation.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  allocation.commandBufferCount = 1;
  VK_OK(vkAllocateCommandBuffers(im->device, &allocation, &im->copy));
  memset(&fence_info, 0, sizeof fence_info);
  fence_info.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO;
  VK_OK(vkCreateFence(im->device, &fence_info, NULL, &im->fence));
}

/* Imports one semaphore's descriptor (the import takes it), permanently, as OpenGL does. */
static VkSemaphore import_semaphore(struct Importer *im, int fd) {
  VkSemaphoreCreateInfo info;
  VkImportSemaphoreFdInfoKHR import;
  VkSemaphore semaphore;
  memset(&info, 0, sizeof info);
  info.sType = VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO;
  VK_OK(vkCreateSemaphore(im->device, &info, NULL, &semaphore));
  memset(&import, 0, sizeof import);
  import.sType = VK_STRUCTURE_TYPE_IMPORT_SEMAPHORE_FD_INFO_KHR;
  import.semaphore = semaphore;
  import.handleType = VK_EXTERNAL_SEMAPHORE_HANDLE_TYPE_OPAQUE_FD_BIT;
  import.fd = fd;
  VK_OK(im->import_semaphore_fd(im->device, &import));
  return semaphore;
}

/* A buffer of `size` bytes bound to memory of its own: imported from `fd` (which the import
 * takes) when `fd` is not -1, host-visible otherwise. */
static VkBuffer dedicated_buffer(struct Importer *im, VkDeviceSize size, int fd,
                                 VkDeviceMemory *memory) {
  VkExternalMemoryBufferCreateInfo external;
  VkBufferCreateInfo buffer_info;
  VkMemoryRequirements needs;
  VkImportMemoryFdInfoKHR import;
  VkMemoryDedicatedAllocateInfo dedicated;
  VkMemoryAllocateInfo allocation;
  VkBuffer buffer;
  memset(&external, 0, sizeof external);
  external.sType = VK_STRUCTURE_TYPE_EXTERNAL_MEMORY_BUFFER_CREATE_INFO;
  external.handleTypes = VK_EXTERNAL_MEMORY_HANDLE_TYPE_OPAQUE_FD_BIT;
  memset(&buffer_info, 0, sizeof buffer_info);
  buffer_info.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
  buffer_info.pNext = fd >= 0 ? &external : NULL;
  buffer_info.size = size;
  buffer_info.usage = fd >= 0 ? VK_BUFFER_USAGE_TRANSFER_SRC_BIT : VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  VK_OK(vkCreateBuffer(im->device, &buffer_info, NULL, &buffer));
  vkGetBufferMemoryRequirements(im->device, buffer, &needs);
  memset(&allocation, 0, sizeof allocation);
  allocation.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
  if (fd >= 0) {
    /* The exporter's size and memory type (the first device-local one the buffer allows), and
     * dedicated to the buffer, as the exported memory is. */
    memset(&dedicated, 0, sizeof dedicated);
    dedicated.sType = VK_STRUCTURE_TYPE_MEMORY_DEDICATED_ALLOCATE_INFO;
    dedicated.buffer = buffer;
    memset(&import, 0, sizeof import);
    import.sType = VK_STRUCTURE_TYPE_IMPORT_MEMORY_FD_INFO_KHR;
    import.pNext = &dedicated;
    import.handleType = VK_EXTERNAL_MEMORY_HANDLE_TYPE_OPAQUE_FD_BIT;
    import.fd = fd;
    allocation.pNext = &import;
    allocation.allocationSize = size;
    allocation.memoryTypeIndex =
        memory_type(im->physical, needs.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
  } else {
    allocation.allocationSize = needs.size;
    allocation.memoryTypeIndex =
        memory_type(im->physical, needs.memoryTypeBits,
                    VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
  }
  VK_OK(vkAllocateMemory(im->device, &allocation, NULL, memory));
  VK_OK(vkBindBufferMemory(im->device, buffer, *memory, 0));
  return buffer;
}

static void release_memory(struct Importer *im, struct Imported *frames) {
  if (frames->shared == VK_NULL_HANDLE) {
    return;
  }
  vkUnmapMemory(im->device, frames->readable_memory);
  vkDestroyBuffer(im->device, frames->shared, NULL);
  vkFreeMemory(im->device, frames->shared_memory, NULL);
  vkDestroyBuffer(im->device, frames->readable, NULL);
  vkFreeMemory(im->device, frames->readable_memory, NULL);
  memset(frames, 0, sizeof *frames);
}

/* Imports the renderer's exported memory (again after a resize), as an OpenGL host does. */
static void import_memory(struct Importer *im, CadrRenderer renderer, struct Imported *frames) {
  CadrExportedFrame exported;
  void *mapped = NULL;
  memset(&exported, 0, sizeof exported);
  exported.size = sizeof exported;
  OK(cadr_renderer_exported_frame(renderer, &exported));
  release_memory(im, frames);
  frames->shared = dedicated_buffer(im, exported.allocation_size, exported.fd,
                                    &frames->shared_memory);
  frames->readable = dedicated_buffer(im, (VkDeviceSize)exported.row_bytes * exported.height, -1,
                                      &frames->readable_memory);
  VK_OK(vkMapMemory(im->device, frames->readable_memory, 0, VK_WHOLE_SIZE, 0, &mapped));
  frames->pixels = mapped;
  frames->generation = exported.generation;
  frames->width = exported.width;
  frames->height = exported.height;
}

/* The host's turn for one frame: waits for `ready`, copies the frame out of the shared memory,
 * signals `released` when `release` (a host that does not is the error case), and waits for
 * its own copy. */
static void read_frame(struct Importer *im, struct Imported *frames, int release) {
  VkCommandBufferBeginInfo begin;
  VkBufferCopy region;
  VkSubmitInfo submit;
  VkPipelineStageFlags stage = VK_PIPELINE_STAGE_TRANSFER_BIT;
  memset(&begin, 0, sizeof begin);
  begin.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO;
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  VK_OK(vkBeginCommandBuffer(im->copy, &begin));
  memset(&region, 0, sizeof region);
  region.size = (VkDeviceSize)frames->width * frames->height * 4;
  vkCmdCopyBuffer(im->copy, frames->shared, frames->readable, 1, &region);
  VK_OK(vkEndCommandBuffer(im->copy));
  memset(&submit, 0, sizeof submit);
  submit.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO;
  submit.waitSemaphoreCount = 1;
  submit.pWaitSemaphores = &im->ready;
  submit.pWaitDstStageMask = &stage;
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &im->copy;
  submit.signalSemaphoreCount = release ? 1 : 0;
  submit.pSignalSemaphores = &im->released;
  VK_OK(vkQueueSubmit(im->queue, 1, &submit, im->fence));
  VK_OK(vkWaitForFences(im->device, 1, &im->fence, VK_TRUE, IMPORTER_TIMEOUT));
  VK_OK(vkResetFences(im->device, 1, &im->fence));
}

/* Signals `released` alone, as a host that releases a frame late does. */
static void signal_released(struct Importer *im) {
  VkSubmitInfo submit;
  memset(&submit, 0, sizeof submit);
  submit.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO;
  submit.signalSemaphoreCount = 1;
  submit.pSignalSemaphores = &im->released;
  VK_OK(vkQueueSubmit(im->queue, 1, &submit, VK_NULL_HANDLE));
}

static void importer_destroy(struct Importer *im, struct Imported *frames) {
  VK_OK(vkDeviceWaitIdle(im->device));
  release_memory(im, frames);
  vkDestroySemaphore(im->device, im->ready, NULL);
  vkDestroySemaphore(im->device, im->released, NULL);
  vkDestroyFence(im->device, im->fence, NULL);
  vkDestroyCommandPool(im->device, im->pool, NULL);
  vkDestroyDevice(im->device, NULL);
  vkDestroyInstance(im->instance, NULL);
}

/* Renders frame `index` of an orbit, has the host read it, and checks that what the host read
 * is the renderer's picture and not the frame before (`previous`, kept). */
static void hand_over(CadrRenderer renderer, CadrScene scene, struct Importer *im,
                      struct Imported *frames, int index, uint8_t *previous) {
  static uint8_t picture[W * H * 4];
  struct CadrBounds bounds;
  struct CadrCamera camera;
  double turn = 0.7 * index, direction[3];
  size_t bytes = (size_t)frames->width * frames->height * 4;
  direction[0] = cos(turn);
  direction[1] = sin(turn);
  direction[2] = 0.5;
  OK(cadr_scene_bounds(scene, &bounds));
  OK(cadr_camera_fit(&bounds, (double)frames->width / frames->height, direction, &camera));
  OK(cadr_renderer_render(renderer, scene, &camera, NULL));
  read_frame(im, frames, 1);
  OK(cadr_renderer_read_pixels(renderer, picture, bytes));
  CHECK(memcmp(frames->pixels, picture, bytes) == 0);
  CHECK(previous == NULL || memcmp(previous, picture, bytes) != 0);
  if (previous != NULL) {
    memcpy(previous, picture, bytes);
  }
}

/* The calls' bad arguments: none changes the renderer. */
static void refused_arguments(CadrContext context, CadrRenderer exporting) {
  CadrExportedSemaphores semaphores;
  CadrRenderer offscreen = 0;
  memset(&semaphores, 0, sizeof semaphores);
  semaphores.size = sizeof semaphores;
  CHECK(cadr_renderer_export_semaphores(exporting, NULL) == CADR_RESULT_NULL_ARGUMENT);
  semaphores.size = 8; /* an older or broken size: the descriptors would not fit */
  CHECK(cadr_renderer_export_semaphores(exporting, &semaphores) == CADR_RESULT_INVALID_ARGUMENT);
  CHECK(strstr(last_error(), "CadrExportedSemaphores") != NULL);
  semaphores.size = sizeof semaphores;
  OK(cadr_renderer_create(context, W, H, &offscreen));
  CHECK(cadr_renderer_export_semaphores(offscreen, &semaphores) == CADR_RESULT_INVALID_ARGUMENT);
  CHECK(strstr(last_error(), "cadr_renderer_create_for_export") != NULL);
  OK(cadr_renderer_destroy(offscreen));
  CHECK(cadr_renderer_export_semaphores(offscreen, &semaphores) == CADR_RESULT_DESTROYED_HANDLE);
  CHECK(cadr_renderer_export_semaphores(NULL, &semaphores) == CADR_RESULT_NULL_ARGUMENT);
  CHECK(cadr_renderer_export_semaphores((CadrRenderer)(uintptr_t)context, &semaphores) ==
        CADR_RESULT_FOREIGN_HANDLE);
}

int main(void) {
  static uint8_t previous[W * H * 4];
  struct CadrContextOptions options = {.size = sizeof(struct CadrContextOptions)};
  struct CadrLoadResult loaded = {.size = sizeof(struct CadrLoadResult)};
  CadrExportedFrame exported;
  CadrExportedSemaphores semaphores;
  CadrContext context = 0;
  CadrScene scene = 0;
  CadrNode root = 0;
  CadrRenderer renderer = 0;
  struct Importer im;
  struct Imported frames;
  enum CadrResult shared;
  uint64_t errors = 99;
  int frame;

  OK(cadr_context_options_default(&options));
  options.validation = true;
  OK(cadr_context_create(&options, &context));
  OK(cadr_scene_create(&scene));
  OK(cadr_scene_root(scene, &root));
  OK(cadr_scene_load(scene, "gen:demo", root, &loaded));
  cadr_load_result_free(&loaded);
  if (cadr_renderer_create_for_export(context, W, H, &renderer) != CADR_RESULT_OK) {
    fprintf(stderr, "this driver cannot export frames at all: %s\n", last_error());
    return 1;
  }
  refused_arguments(context, renderer);

  memset(&exported, 0, sizeof exported);
  exported.size = sizeof exported;
  OK(cadr_renderer_exported_frame(renderer, &exported));
  close(exported.fd);
  importer_find_device(&im, exported.device_uuid);
  memset(&semaphores, 0, sizeof semaphores);
  semaphores.size = sizeof semaphores;
  shared = cadr_renderer_export_semaphores(renderer, &semaphores);
  if (shared == CADR_RESULT_UNSUPPORTED) {
    /* Refused for a reason the driver really has, the frames still waited for. */
    CHECK(strstr(last_error(), "VK_KHR_external_semaphore_fd") != NULL);
    CHECK(!has_extension(im.physical, "VK_KHR_external_semaphore_fd"));
    vkDestroyInstance(im.instance, NULL);
    OK(cadr_renderer_destroy(renderer));
    OK(cadr_context_validation_error_count(context, &errors));
    CHECK(errors == 0);
    OK(cadr_context_destroy(context));
    OK(cadr_scene_destroy(scene));
    printf("semaphores unsupported (frames waited for); checks passed\n");
    return 0;
  }
  OK(shared);
  CHECK(semaphores.ready_fd >= 0 && semaphores.released_fd >= 0);
  importer_create_device(&im);
  im.ready = import_semaphore(&im, semaphores.ready_fd);
  im.released = import_semaphore(&im, semaphores.released_fd);
  {
    /* A second call gives new descriptors of the same semaphores. */
    CadrExportedSemaphores again = {.size = sizeof(CadrExportedSemaphores)};
    OK(cadr_renderer_export_semaphores(renderer, &again));
    CHECK(again.ready_fd >= 0 && again.ready_fd != semaphores.ready_fd);
    close(again.ready_fd);
    close(again.released_fd);
  }
  memset(&frames, 0, sizeof frames);
  import_memory(&im, renderer, &frames);

  for (frame = 0; frame < FRAMES; ++frame) {
    hand_over(renderer, scene, &im, &frames, frame, previous);
  }
  /* A resize puts the frames in new memory; the semaphores stay. */
  OK(cadr_renderer_resize(renderer, W2, H2));
  import_memory(&im, renderer, &frames);
  CHECK(frames.width == W2 && frames.height == H2);
  for (frame = 0; frame < FRAMES; ++frame) {
    hand_over(renderer, scene, &im, &frames, frame, NULL);
  }
  OK(cadr_context_validation_error_count(context, &errors));
  CHECK(errors == 0);

  {
    /* A host that reads a frame and does not release it: the next frame's copy waits for the
     * release, and the render after it is refused, naming the semaphore, once cadr has waited
     * 10 s, having drawn nothing. Released late, the waiting copy hands its frame over, and
     * frames go on. */
    struct CadrBounds bounds;
    struct CadrCamera camera;
    static uint8_t picture[W2 * H2 * 4];
    OK(cadr_scene_bounds(scene, &bounds));
    OK(cadr_camera_fit(&bounds, (double)W2 / H2, NULL, &camera));
    OK(cadr_renderer_render(renderer, scene, &camera, NULL));
    read_frame(&im, &frames, 0);
    OK(cadr_renderer_render(renderer, scene, &camera, NULL));
    CHECK(cadr_renderer_render(renderer, scene, &camera, NULL) == CADR_RESULT_INVALID_ARGUMENT);
    CHECK(strstr(last_error(), "released") != NULL);
    signal_released(&im);
    read_frame(&im, &frames, 1);
    OK(cadr_renderer_read_pixels(renderer, picture, sizeof picture));
    CHECK(memcmp(frames.pixels, picture, sizeof picture) == 0);
    hand_over(renderer, scene, &im, &frames, 0, NULL);
    OK(cadr_renderer_destroy(renderer));
    OK(cadr_context_validation_error_count(context, &errors));
    CHECK(errors == 0);
  }
  importer_destroy(&im, &frames);
  OK(cadr_context_destroy(context));
  OK(cadr_scene_destroy(scene));
  printf("semaphores shared: %d frames handed over by semaphores; checks passed\n", 2 * FRAMES + 3);
  return 0;
}
