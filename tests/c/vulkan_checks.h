/* What the C test programs that make Vulkan objects of their own (host_vulkan.c,
 * export_semaphores.c) share: VK_OK for a Vulkan call that must succeed, exiting non-zero with
 * the place and the result on failure, and memory_type to choose memory. */
#ifndef CADR_TEST_VULKAN_CHECKS_H
#define CADR_TEST_VULKAN_CHECKS_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <vulkan/vulkan.h>

#define VK_OK(call)                                                                  \
  do {                                                                               \
    VkResult vk_result_ = (call);                                                    \
    if (vk_result_ != VK_SUCCESS) {                                                  \
      fprintf(stderr, "%s:%d: %s gave %d\n", __FILE__, __LINE__, #call, vk_result_); \
      exit(1);                                                                       \
    }                                                                                \
  } while (0)

/* The first memory type of `physical` among `bits` with `flags` (the choice cadr makes for the
 * memory it exports, with VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT); exits when there is none. */
static inline uint32_t memory_type(VkPhysicalDevice physical, uint32_t bits,
                                   VkMemoryPropertyFlags flags) {
  VkPhysicalDeviceMemoryProperties memory;
  uint32_t i;
  vkGetPhysicalDeviceMemoryProperties(physical, &memory);
  for (i = 0; i < memory.memoryTypeCount; ++i) {
    if ((bits & (1u << i)) && (memory.memoryTypes[i].propertyFlags & flags) == flags) {
      return i;
    }
  }
  fprintf(stderr, "no memory type with flags %x\n", (unsigned)flags);
  exit(1);
}

#endif
