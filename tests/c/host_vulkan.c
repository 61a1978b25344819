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

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <vulkan/vulkan.h>

enum { W = 96, H = 72 };

static const char *last_error(void) {
  static char text[4096];
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

#define VK_OK(call)                                                                  \
  do {                                                                               \
    VkResult vk_result_ = (call);                                                    \
    if (vk_result_ != VK_SUCCESS) {                                                  \
      fprintf(stderr, "%s:%d: %s gave %d\n", __FILE__, __LINE__, #call, vk_result_); \
      exit(1);                                                                       \
    }                                                                                \
  } while (0)

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

/* Draws gen:demo with a renderer of `context` into `pixels`. */
static void draw_demo(CadrContext context, CadrScene scene, uint8_t *pixels) {
  CadrRenderer renderer = 0;
  struct CadrBounds bounds;
  struct CadrCamera camera;
  struct CadrFrameStats stats;
  int frame;
  OK(cadr_scene_bounds(scene, &bounds));
  OK(cadr_camera_fit(&bounds, (double)W / H, NULL, &camera));
  OK(cadr_renderer_create(context, W, H, &renderer));
  OK(cadr_renderer_set_frames_in_flight(renderer, 3));
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
  struct CadrVulkanRequirements requirements;
  float priority = 1.0f;
  VkDeviceQueueCreateInfo queue_info;
  VkDeviceCreateInfo device_info;
  VkDevice device;
  struct QueueLock lock;
  struct CadrHostVulkan host;
  struct CadrContextOptions options;
  CadrContext lent = 0, own = 0;
  CadrScene scene = 0;
  CadrNode root = 0;
  struct CadrLoadResult loaded;
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
