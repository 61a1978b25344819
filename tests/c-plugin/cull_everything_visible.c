/* A technique plugin written in C: a culler that lets every candidate through. It shows that
 * include/cadr_plugin.h is all a C or C++ author needs. Built and loaded by
 * tests/tests/techniques.rs; compiled as strict C99 and C++ by plugins/abi/tests/header.rs. */
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

/* Visible bits become the candidate bits; changed bits are their XOR with the last frame's. */
static CadrStatus cull(void *instance, const CadrCullInput *input, CadrCullOutput *output,
                       CadrMessage *message) {
    uint32_t word;
    (void)instance;
    if (input == NULL || output == NULL || input->candidate_bits == NULL) {
        if (message != NULL && message->text != NULL && message->capacity > 16) {
            strcpy(message->text, "missing input");
        }
        return CADR_STATUS_ERROR;
    }
    for (word = 0; word < output->word_count; ++word) {
        uint64_t visible = input->candidate_bits[word];
        output->changed_bits[word] = output->visible_bits[word] ^ visible;
        output->visible_bits[word] = visible;
    }
    return CADR_STATUS_OK;
}

static CadrCullingVtable vtable;
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
    vtable.cull = cull;
    memset(&technique, 0, sizeof technique);
    technique.size = sizeof technique;
    technique.kind = CADR_KIND_CULLING;
    technique.name = "c-candidates";
    technique.description = "Written in C: draws every candidate.";
    technique.vtable = &vtable;
    memset(&filled, 0, sizeof filled);
    filled.size = sizeof filled;
    filled.abi_major = CADR_PLUGIN_ABI_MAJOR;
    filled.abi_minor = CADR_PLUGIN_ABI_MINOR;
    filled.name = "cadr C example";
    filled.technique_count = 1;
    filled.techniques = &technique;
    room = library->size < sizeof filled ? library->size : sizeof filled;
    memcpy(library, &filled, room);
    library->size = (uint32_t)room;
    return CADR_STATUS_OK;
}
