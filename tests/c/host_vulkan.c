/* A host that brings its own Vulkan: it creates the instance (with the validation layer) and the
 * device itself, enabling what cadr_vulkan_requirements asks for, and hands them to
 * cadr_context_create_from_vulkan with a lock on the queue they share. cadr must draw what it
 * draws on a device of its own, take the host's lock around every use of the queue, report no
 * validation error, refuse a device without a feature it needs (naming it), and leave the
 * instance and device alive for the host to destroy.
 *
 * Built by tests/tests/c_api.rs with the strict flags and -lvulkan. Exits non-zero on the first
 * failed check. */
#define _POSIX_C_SOURCE 200809L
#include "cadr.h"
#include "checks.h"
#include "vulkan_checks.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <vulkan/vulkan.h>

enum { W = 96, H = 72 };

/* The host's lock on the queue: a mutex, and how often cadr took it. */
struct QueueLock {
  pthread_mutex_t mutex;
  int taken;
  int held;
};

static void lock_queue(void *user) {
  struct QueueLock *lock = user;
  CHECK(pthread_mutex_lock(&lock->mutex) == 0);
  lock->taken += 1;
  lock->held += 1;
}

static void unlock_queue(void *user) {
  struct QueueLock *lock = user;
  lock->held -= 1;
  CHECK(pthread_mutex_unlock(&lock->mutex) == 0);
}

/* The features the host knows how to enable, by cadr's names, with the supported and enabled
 * flags they name. */
struct Features {
  VkPhysicalDeviceFeatures2 core;
  VkPhysicalDeviceVulkan11Features v11;
  VkPhysicalDeviceVulkan12Features v12;
  VkPhysicalDeviceVulkan13Features v13;
};

static void chain(struct Features *f) {
  memset(f, 0, sizeof *f);
  f->core.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2;
  f->v11.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES;
  f->v12.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES;
  f->v13.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES;
  f->core.pNext = &f->v11;
  f->v11.pNext = &f->v12;
  f->v12.pNext = &f->v13;
}

/* The flag `name` ("Struct::member") stands for in `f`, or NULL for one this host leaves off. */
static VkBool32 *flag(struct Features *f, const char *name) {
  static const struct {
    const char *name;
    size_t offset;
  } known[] = {
      {"VkPhysicalDeviceVulkan13Features::dynamicRendering",
       offsetof(struct Features, v13.dynamicRendering)},
      {"VkPhysicalDeviceVulkan13Features::synchronization2",
       offsetof(struct Features, v13.synchronization2)},
      {"VkPhysicalDeviceVulkan13Features::maintenance4", offsetof(struct Features, v13.maintenance4)},
      {"VkPhysicalDeviceFeatures::shaderClipDistance",
       offsetof(struct Features, core.features.shaderClipDistance)},
      {"VkPhysicalDeviceFeatures::fillModeNonSolid",
       offsetof(struct Features, core.features.fillModeNonSolid)},
      {"VkPhysicalDeviceFeatures::independentBlend",
       offsetof(struct Features, core.features.independentBlend)},
      {"VkPhysicalDeviceFeatures::multiDrawIndirect",
       offsetof(struct Features, core.features.multiDrawIndirect)},
      {"VkPhysicalDeviceFeatures::drawIndirectFirstInstance",
       offsetof(struct Features, core.features.drawIndirectFirstInstance)},
      {"VkPhysicalDeviceFeatures::fragmentStoresAndAtomics",
       offsetof(struct Features, core.features.fragmentStoresAndAtomics)},
      {"VkPhysicalDeviceVulkan11Features::shaderDrawParameters",
       offsetof(struct Features, v11.shaderDrawParameters)},
      {"VkPhysicalDeviceVulkan12Features::bufferDeviceAddress",
       offsetof(struct Features, v12.bufferDeviceAddress)},
      {"VkPhysicalDeviceVulkan12Features::drawIndirectCount",
       offsetof(struct Features, v12.drawIndirectCount)},
      {"VkPhysicalDeviceVulkan12Features::hostQueryReset",
       offsetof(struct Features, v12.hostQueryReset)},
  };
  size_t i;
  for (i = 0; i < sizeof known / sizeof known[0]; ++i) {
    if (strcmp(known[i].name, name) == 0) {
      return (VkBool32 *)((char *)f + known[i].offset);
    }
  }
  return NULL;
}

/* The host's side of a frame handed over in its own image: the image, a buffer to read it back,
 * the semaphores around cadr's blit and the host's copy. */
struct Handover {
  VkImage image;
  VkDeviceMemory image_memory;
  VkBuffer buffer;
  VkDeviceMemory buffer_memory;
  VkSemaphore ready, done;
  VkCommandPool pool;
  VkCommandBuffer copy;
  VkFence fence;
};

static void handover_create(struct Handover *h, VkPhysicalDevice physical, VkDevice device,
                            uint32_t family) {
  VkImageCreateInfo image_info;
  VkBufferCreateInfo buffer_info;
  VkMemoryRequirements needs;
  VkMemoryAllocateInfo allocation;
  VkSemaphoreCreateInfo semaphore_info;
  VkCommandPoolCreateInfo pool_info;
  VkCommandBufferAllocateInfo buffer_allocation;
  VkFenceCreateInfo fence_info;
  memset(&image_info, 0, sizeof image_info);
  image_info.sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO;
  image_info.imageType = VK_IMAGE_TYPE_2D;
  image_info.format = VK_FORMAT_R8G8B8A8_UNORM;
  image_info.extent.width = W;
  image_info.extent.height = H;
  image_info.extent.depth = 1;
  image_info.mipLevels = 1;
  image_info.arrayLayers = 1;
  image_info.samples = VK_SAMPLE_COUNT_1_BIT;
  image_info.tiling = VK_IMAGE_TILING_OPTIMAL;
  image_info.usage = VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  VK_OK(vkCreateImage(device, &image_info, NULL, &h->image));
  vkGetImageMemoryRequirements(device, h->image, &needs);
  memset(&allocation, 0, sizeof allocation);
  allocation.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
  allocation.allocationSize = needs.size;
  allocation.memoryTypeIndex =
      memory_type(physical, needs.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
  VK_OK(vkAllocateMemory(device, &allocation, NULL, &h->image_memory));
  VK_OK(vkBindImageMemory(device, h->image, h->image_memory, 0));
  memset(&buffer_info, 0, sizeof buffer_info);
  buffer_info.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
  buffer_info.size = W * H * 4;
  buffer_info.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  VK_OK(vkCreateBuffer(device, &buffer_info, NULL, &h->buffer));
  vkGetBufferMemoryRequirements(device, h->buffer, &needs);
  allocation.allocationSize = needs.size;
  allocation.memoryTypeIndex =
      memory_type(physical, needs.memoryTypeBits,
                  VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
  VK_OK(vkAllocateMemory(device, &allocation, NULL, &h->buffer_memory));
  VK_OK(vkBindBufferMemory(device, h->buffer, h->buffer_memory, 0));
  memset(&semaphore_info, 0, sizeof semaphore_info);
  semaphore_info.sType = VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO;
  VK_OK(vkCreateSemaphore(device, &semaphore_info, NULL, &h->ready));
  VK_OK(vkCreateSemaphore(device, &semaphore_info, NULL, &h->done));
  memset(&pool_info, 0, sizeof pool_info);
  pool_info.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO;
  pool_info.queueFamilyIndex = family;
  VK_OK(vkCreateCommandPool(device, &pool_info, NULL, &h->pool));
  memset(&buffer_allocation, 0, sizeof buffer_allocation);
  buffer_allocation.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO;
  buffer_allocation.commandPool = h->pool;
  buffer_allocation.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  buffer_allocation.commandBufferCount = 1;
  VK_OK(vkAllocateCommandBuffers(device, &buffer_allocation, &h->copy));
  memset(&fence_info, 0, sizeof fence_info);
  fence_info.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO;
  VK_OK(vkCreateFence(device, &fence_info, NULL, &h->fence));
}

/* Signals `ready` (the image may be written), as a host does when it is done with the image. */
static void handover_release(struct Handover *h, VkQueue queue, struct QueueLock *lock) {
  VkSubmitInfo submit;
  memset(&submit, 0, sizeof submit);
  submit.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO;
  submit.signalSemaphoreCount = 1;
  submit.pSignalSemaphores = &h->ready;
  lock_queue(lock);
  VK_OK(vkQueueSubmit(queue, 1, &submit, VK_NULL_HANDLE));
  unlock_queue(lock);
}

/* Copies the image (in TRANSFER_SRC_OPTIMAL once `done` is signalled) into the buffer, waits,
 * and returns the mapped pixels. */
static const uint8_t *handover_read(struct Handover *h, VkDevice device, VkQueue queue,
                                    struct QueueLock *lock) {
  VkCommandBufferBeginInfo begin;
  VkBufferImageCopy region;
  VkSubmitInfo submit;
  VkPipelineStageFlags stage = VK_PIPELINE_STAGE_TRANSFER_BIT;
  void *mapped = NULL;
  memset(&begin, 0, sizeof begin);
  begin.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO;
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  VK_OK(vkBeginCommandBuffer(h->copy, &begin));
  memset(&region, 0, sizeof region);
  region.imageSubresource.aspectMask = VK_IMAGE_ASPECT_COLOR_BIT;
  region.imageSubresource.layerCount = 1;
  region.imageExtent.width = W;
  region.imageExtent.height = H;
  region.imageExtent.depth = 1;
  vkCmdCopyImageToBuffer(h->copy, h->image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, h->buffer, 1,
                         &region);
  VK_OK(vkEndCommandBuffer(h->copy));
  memset(&submit, 0, sizeof submit);
  submit.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO;
  submit.waitSemaphoreCount = 1;
  submit.pWaitSemaphores = &h->done;
  submit.pWaitDstStageMask = &stage;
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &h->copy;
  lock_queue(lock);
  VK_OK(vkQueueSubmit(queue, 1, &submit, h->fence));
  unlock_queue(lock);
  VK_OK(vkWaitForFences(device, 1, &h->fence, VK_TRUE, UINT64_MAX));
  VK_OK(vkMapMemory(device, h->buffer_memory, 0, VK_WHOLE_SIZE, 0, &mapped));
  return mapped;
}

static void handover_destroy(struct Handover *h, VkDevice device) {
  vkUnmapMemory(device, h->buffer_memory);
  vkDestroyFence(device, h->fence, NULL);
  vkDestroyCommandPool(device, h->pool, NULL);
  vkDestroySemaphore(device, h->ready, NULL);
  vkDestroySemaphore(device, h->done, NULL);
  vkDestroyBuffer(device, h->buffer, NULL);
  vkFreeMemory(device, h->buffer_memory, NULL);
  vkDestroyImage(device, h->image, NULL);
  vkFreeMemory(device, h->image_memory, NULL);
}

/* Draws gen:demo with a renderer of `context` into `pixels`. */
static void draw_demo(CadrContext context, CadrScene scene, uint8_t *pixels) {
  CadrRenderer renderer = 0;
  struct CadrBounds bounds;
  struct CadrCamera camera;
  struct CadrFrameStats stats = {.size = sizeof(struct CadrFrameStats)};
  int frame;
  OK(cadr_scene_bounds(scene, &bounds));
  OK(cadr_camera_fit(&bounds, (double)W / H, NULL, &camera));
  OK(cadr_renderer_create(context, W, H, &renderer));
  OK(set_frames_in_flight(renderer, 3));
  for (frame = 0; frame < 4; ++frame) {
    OK(cadr_renderer_render(renderer, scene, &camera, &stats));
  }
  OK(cadr_renderer_read_pixels(renderer, pixels, W * H * 4));
  OK(cadr_renderer_destroy(renderer));
}

int main(void) {
  static uint8_t lent_pixels[W * H * 4], own_pixels[W * H * 4];
  const char *layers[1] = {"VK_LAYER_KHRONOS_validation"};
  const char *instance_extensions[1] = {VK_EXT_DEBUG_UTILS_EXTENSION_NAME};
  VkApplicationInfo app;
  VkInstanceCreateInfo instance_info;
  VkInstance instance;
  VkPhysicalDevice physicals[8], physical = VK_NULL_HANDLE;
  uint32_t physical_count = 8, family = 0, i;
  struct Features supported, enabled;
  struct CadrVulkanRequirements requirements = {.size = sizeof(struct CadrVulkanRequirements)};
  float priority = 1.0f;
  VkDeviceQueueCreateInfo queue_info;
  VkDeviceCreateInfo device_info;
  VkDevice device;
  struct QueueLock lock;
  struct CadrHostVulkan host = {.size = sizeof(struct CadrHostVulkan)};
  struct CadrContextOptions options = {.size = sizeof(struct CadrContextOptions)};
  CadrContext lent = 0, own = 0;
  CadrScene scene = 0;
  CadrNode root = 0;
  struct CadrLoadResult loaded = {.size = sizeof(struct CadrLoadResult)};
  uint64_t errors = 99;

  memset(&app, 0, sizeof app);
  app.sType = VK_STRUCTURE_TYPE_APPLICATION_INFO;
  app.pApplicationName = "cadr host test";
  app.apiVersion = VK_API_VERSION_1_3;
  memset(&instance_info, 0, sizeof instance_info);
  instance_info.sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO;
  instance_info.pApplicationInfo = &app;
  instance_info.enabledLayerCount = 1;
  instance_info.ppEnabledLayerNames = layers;
  instance_info.enabledExtensionCount = 1;
  instance_info.ppEnabledExtensionNames = instance_extensions;
  VK_OK(vkCreateInstance(&instance_info, NULL, &instance));

  /* The first device with Vulkan 1.3 and a graphics and compute queue family. */
  VK_OK(vkEnumeratePhysicalDevices(instance, &physical_count, physicals));
  for (i = 0; i < physical_count && physical == VK_NULL_HANDLE; ++i) {
    VkPhysicalDeviceProperties properties;
    VkQueueFamilyProperties families[16];
    uint32_t family_count = 16, f;
    vkGetPhysicalDeviceProperties(physicals[i], &properties);
    if (properties.apiVersion < VK_API_VERSION_1_3) {
      continue;
    }
    vkGetPhysicalDeviceQueueFamilyProperties(physicals[i], &family_count, families);
    for (f = 0; f < family_count; ++f) {
      if ((families[f].queueFlags & (VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT)) ==
          (VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT)) {
        physical = physicals[i];
        family = f;
        break;
      }
    }
  }
  CHECK(physical != VK_NULL_HANDLE);

  /* Every required feature (the host must know each), and the optional ones it knows where the
   * device has them. */
  memset(&requirements, 0, sizeof requirements);
  requirements.size = sizeof requirements;
  requirements.size = sizeof requirements;
  OK(cadr_vulkan_requirements(&requirements));
  CHECK(requirements.api_version == VK_API_VERSION_1_3);
  CHECK(requirements.required_feature_count > 0);
  {
    /* A newer host's longer struct: what this library knows, and zeros beyond; a size too
     * small to hold the size is refused. */
    struct {
      struct CadrVulkanRequirements known;
      uint64_t added_later;
    } newer;
    memset(&newer, 0xab, sizeof newer);
    newer.known.size = sizeof newer;
    OK(cadr_vulkan_requirements(&newer.known));
    CHECK(newer.known.size == sizeof newer);
    CHECK(newer.known.required_feature_count == requirements.required_feature_count);
    CHECK(newer.added_later == 0);
    newer.known.size = 2;
    CHECK(cadr_vulkan_requirements(&newer.known) == CADR_RESULT_INVALID_ARGUMENT);
    CHECK(cadr_vulkan_requirements(NULL) == CADR_RESULT_NULL_ARGUMENT);
  }
  chain(&supported);
  vkGetPhysicalDeviceFeatures2(physical, &supported.core);
  chain(&enabled);
  for (i = 0; i < requirements.required_feature_count; ++i) {
    VkBool32 *has = flag(&supported, requirements.required_features[i]);
    if (has == NULL || !*has) {
      fprintf(stderr, "cannot enable %s\n", requirements.required_features[i]);
      return 1;
    }
    *flag(&enabled, requirements.required_features[i]) = VK_TRUE;
  }
  for (i = 0; i < requirements.optional_feature_count; ++i) {
    VkBool32 *has = flag(&supported, requirements.optional_features[i]);
    if (has != NULL && *has) {
      *flag(&enabled, requirements.optional_features[i]) = VK_TRUE;
    }
  }
  memset(&queue_info, 0, sizeof queue_info);
  queue_info.sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO;
  queue_info.queueFamilyIndex = family;
  queue_info.queueCount = 1;
  queue_info.pQueuePriorities = &priority;
  memset(&device_info, 0, sizeof device_info);
  device_info.sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO;
  device_info.pNext = &enabled.core;
  device_info.queueCreateInfoCount = 1;
  device_info.pQueueCreateInfos = &queue_info;
  VK_OK(vkCreateDevice(physical, &device_info, NULL, &device));

  CHECK(pthread_mutex_init(&lock.mutex, NULL) == 0);
  lock.taken = 0;
  lock.held = 0;
  memset(&host, 0, sizeof host);
  host.size = sizeof host;
  host.size = sizeof host;
  host.get_instance_proc_addr = (CadrGetInstanceProcAddr)vkGetInstanceProcAddr;
  host.instance = instance;
  host.instance_extensions = instance_extensions;
  host.instance_extension_count = 1;
  host.physical_device = physical;
  host.device = device;
  host.device_create_info = &device_info;
  host.queue_family = family;
  host.queue_index = 0;
  host.lock_queue = lock_queue;
  host.unlock_queue = unlock_queue;
  host.queue_user = &lock;

  /* Refused clearly: a device without dynamic rendering, a lock without an unlock, no device. */
  enabled.v13.dynamicRendering = VK_FALSE;
  CHECK(cadr_context_create_from_vulkan(&host, NULL, &lent) == CADR_RESULT_UNSUPPORTED);
  CHECK(strstr(last_error(), "VkPhysicalDeviceVulkan13Features::dynamicRendering") != NULL);
  enabled.v13.dynamicRendering = VK_TRUE;
  host.unlock_queue = NULL;
  CHECK(cadr_context_create_from_vulkan(&host, NULL, &lent) == CADR_RESULT_INVALID_ARGUMENT);
  host.unlock_queue = unlock_queue;
  host.device = NULL;
  CHECK(cadr_context_create_from_vulkan(&host, NULL, &lent) == CADR_RESULT_INVALID_ARGUMENT);
  CHECK(strstr(last_error(), "host.device") != NULL);
  host.device = device;
  CHECK(cadr_context_create_from_vulkan(NULL, NULL, &lent) == CADR_RESULT_NULL_ARGUMENT);
  CHECK(lock.taken == 0);

  OK(cadr_context_create_from_vulkan(&host, NULL, &lent));
  OK(cadr_scene_create(&scene));
  OK(cadr_scene_root(scene, &root));
  OK(cadr_scene_load(scene, "gen:demo", root, &loaded));
  cadr_load_result_free(&loaded);
  draw_demo(lent, scene, lent_pixels);
  CHECK(lock.taken > 0);
  CHECK(lock.held == 0);
  {
    /* The host did not enable VK_KHR_external_memory_fd: frames cannot be exported. */
    CadrRenderer exporting = NULL;
    CHECK(cadr_renderer_create_for_export(lent, W, H, &exporting) == CADR_RESULT_UNSUPPORTED);
    CHECK(strstr(last_error(), "VK_KHR_external_memory_fd") != NULL);
    CHECK(exporting == NULL);
  }
  {
    /* Frames into the host's own image: cadr's blit waits for the host's `ready` and signals
     * `done`, which the host's copy waits for; the image holds the renderer's picture. */
    struct Handover h;
    struct CadrHostImage image = {.size = sizeof(struct CadrHostImage)};
    static uint8_t picture[W * H * 4];
    const uint8_t *handed;
    CadrRenderer renderer = 0;
    struct CadrBounds bounds;
    struct CadrCamera camera;
    struct CadrFrameStats stats = {.size = sizeof(struct CadrFrameStats)};
    VkQueue queue;
    vkGetDeviceQueue(device, family, 0, &queue);
    handover_create(&h, physical, device, family);
    memset(&image, 0, sizeof image);
    image.size = sizeof image;
    image.size = sizeof image;
    image.image = (uint64_t)(uintptr_t)h.image;
    image.format = VK_FORMAT_BC1_RGB_UNORM_BLOCK; /* compressed: never a blit destination */
    image.width = W;
    image.height = H;
    image.old_layout = VK_IMAGE_LAYOUT_UNDEFINED;
    image.new_layout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
    image.wait_semaphore = (uint64_t)(uintptr_t)h.ready;
    image.signal_semaphore = (uint64_t)(uintptr_t)h.done;
    CHECK(cadr_renderer_create_for_image(lent, &image, &renderer) == CADR_RESULT_UNSUPPORTED);
    CHECK(strstr(last_error(), "BC1_RGB_UNORM_BLOCK") != NULL);
    image.format = VK_FORMAT_R8G8B8A8_UNORM;
    image.new_layout = VK_IMAGE_LAYOUT_UNDEFINED;
    CHECK(cadr_renderer_create_for_image(lent, &image, &renderer) == CADR_RESULT_INVALID_ARGUMENT);
    image.new_layout = VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL;
    OK(cadr_renderer_create_for_image(lent, &image, &renderer));
    CHECK(cadr_renderer_resize(renderer, 10, 10) == CADR_RESULT_INVALID_ARGUMENT);
    OK(cadr_scene_bounds(scene, &bounds));
    OK(cadr_camera_fit(&bounds, (double)W / H, NULL, &camera));
    handover_release(&h, queue, &lock);
    OK(cadr_renderer_render(renderer, scene, &camera, &stats));
    handed = handover_read(&h, device, queue, &lock);
    OK(cadr_renderer_read_pixels(renderer, picture, sizeof picture));
    CHECK(memcmp(handed, picture, sizeof picture) == 0);
    CHECK(pixel_difference(picture, lent_pixels, sizeof picture) == 0);
    OK(cadr_renderer_destroy(renderer));
    handover_destroy(&h, device);
  }
  OK(cadr_context_validation_error_count(lent, &errors));
  CHECK(errors == 0);
  OK(cadr_context_destroy(lent));

  /* The same scene on a device of cadr's own, made after the host's context is gone: Debian
   * 12's validation layer (1.3.239) keeps per process whether it wraps handles, and cadr's own
   * instance turns the wrapping off (for the device-generated-commands extension, which that
   * layer does not know), which the host's instance, made with it on, does not survive. */
  OK(cadr_context_options_default(&options));
  options.validation = true;
  OK(cadr_context_create(&options, &own));
  draw_demo(own, scene, own_pixels);
  CHECK(pixel_difference(lent_pixels, own_pixels, sizeof own_pixels) == 0);
  /* Something is drawn: the centre is not the background of the corner. */
  CHECK(pixel_difference(lent_pixels, lent_pixels + ((H / 2) * W + W / 2) * 4, 4) == 1);
  OK(cadr_context_destroy(own));
  OK(cadr_scene_destroy(scene));

  /* The device and instance are still the host's. */
  VK_OK(vkDeviceWaitIdle(device));
  vkDestroyDevice(device, NULL);
  vkDestroyInstance(instance, NULL);
  CHECK(pthread_mutex_destroy(&lock.mutex) == 0);
  printf("host vulkan: %d uses of the shared queue; checks passed\n", lock.taken);
  return 0;
}
