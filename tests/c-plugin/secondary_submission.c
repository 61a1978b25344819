/* A submission technique written in C that says it records secondary command buffers
 * (CADR_TRAIT_SECONDARY_COMMAND_BUFFERS) and records nothing. Built against the header as
 * released for ABI 1.0 by tests/tests/techniques.rs, to check that the host refuses to draw with
 * it under MSAA: before ABI 1.8 a submission's secondary command buffers inherit one sample per
 * pixel. */
#include "cadr_plugin.h"

#include <string.h>

#if defined(__cplusplus)
#define CADR_EXPORT extern "C" __attribute__((visibility("default")))
#else
#define CADR_EXPORT __attribute__((visibility("default")))
#endif

static int instance_token;

static CadrStatus create(const CadrCreateInfo *info, void **instance, CadrMessage *message) {
    (void)message;
    if (info == NULL || instance == NULL) {
        return CADR_STATUS_ERROR;
    }
    *instance = &instance_token;
    return CADR_STATUS_OK;
}

static void destroy(void *instance) {
    (void)instance;
}

static CadrStatus prepare(void *instance, const CadrRecordContext *context, CadrMessage *message) {
    (void)instance;
    (void)context;
    (void)message;
    return CADR_STATUS_OK;
}

/* Records no secondary command buffer: the pass draws nothing. */
static CadrStatus record(void *instance, const CadrRecordContext *context, CadrMessage *message) {
    (void)instance;
    (void)context;
    (void)message;
    return CADR_STATUS_OK;
}

static CadrSubmissionVtable vtable;
static CadrTechniqueInfo technique;

CADR_EXPORT uint32_t cadr_plugin_abi_version(void) {
    return CADR_PLUGIN_ABI_VERSION;
}

CADR_EXPORT CadrStatus cadr_plugin_entry(CadrPluginLibrary *library) {
    CadrPluginLibrary filled;
    size_t room;
    if (library == NULL) {
        return CADR_STATUS_ERROR;
    }
    memset(&vtable, 0, sizeof vtable);
    vtable.common.size = sizeof vtable;
    vtable.common.create = create;
    vtable.common.destroy = destroy;
    vtable.prepare = prepare;
    vtable.record = record;
    memset(&technique, 0, sizeof technique);
    technique.size = sizeof technique;
    technique.kind = CADR_KIND_SUBMISSION;
    technique.name = "c-secondary";
    technique.description = "Written in C: records secondary command buffers (none).";
    technique.provides = CADR_TRAIT_SECONDARY_COMMAND_BUFFERS;
    technique.vtable = &vtable;
    memset(&filled, 0, sizeof filled);
    filled.size = sizeof filled;
    filled.abi_major = CADR_PLUGIN_ABI_MAJOR;
    filled.abi_minor = CADR_PLUGIN_ABI_MINOR;
    filled.name = "cadr C secondary-buffer fixture";
    filled.technique_count = 1;
    filled.techniques = &technique;
    room = library->size < sizeof filled ? library->size : sizeof filled;
    memcpy(library, &filled, room);
    library->size = (uint32_t)room;
    return CADR_STATUS_OK;
}
