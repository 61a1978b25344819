/* Linked into the AddressSanitizer build of the C suite only: dlclose keeps every library
 * mapped until the process exits. The Vulkan loader unloads its drivers and layers when an
 * instance is destroyed; what they kept for the process would then be reported as leaks of an
 * "unknown module" that no suppression can name. cadr itself never unloads plugins. */
#include <stddef.h>

int dlclose(void *handle);

int dlclose(void *handle) {
  (void)handle;
  return 0;
}
