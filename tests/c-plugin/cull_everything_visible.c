/* A technique plugin written in C: a culler that lets every candidate through. It shows that
 * include/cadr_plugin.h is all a C or C++ author needs. Built and loaded by
 * tests/tests/techniques.rs; compiled as strict C99 and C++ by plugins/abi/tests/header.rs.
 *
 * Built with CADR_FIXTURE_NEWER_MINOR, it is what a library of the next minor version looks
 * like to this host: it says it was built for one minor more, its technique description is
 * longer than this header's (as if the next minor had added a field), and it offers an
 * extension no host knows yet. With CADR_FIXTURE_REQUIRES_UNKNOWN it also requires that
 * extension, and a host must refuse it. */
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

#if defined(CADR_FIXTURE_NEWER_MINOR)
#define FIXTURE_ABI_MINOR (CADR_PLUGIN_ABI_MINOR + 1)
/* The extension kind the fixture offers (and may require): no host defines it. */
#define FIXTURE_EXTENSION_KIND 0x7fff0001u
typedef struct FixtureExtension {
    CadrExtension header;
    uint32_t value;
} FixtureExtension;
typedef struct NewerTechniqueInfo {
    CadrTechniqueInfo known;
    uint64_t added_by_the_next_minor;
} NewerTechniqueInfo;
static FixtureExtension offered;
#if defined(CADR_FIXTURE_REQUIRES_UNKNOWN)
static const CadrExtensionKind required[1] = {FIXTURE_EXTENSION_KIND};
#endif
static NewerTechniqueInfo newer;
#define technique (newer.known)
#else
#define FIXTURE_ABI_MINOR CADR_PLUGIN_ABI_MINOR
static CadrTechniqueInfo technique;
#endif

CADR_EXPORT uint32_t cadr_plugin_abi_version(void) {
    return ((uint32_t)CADR_PLUGIN_ABI_MAJOR << 16) | FIXTURE_ABI_MINOR;
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
    /* It writes nothing the GPU reads, so it keeps its per-frame data per frame slot as it is.
     * Built against the 1.0 header, the same bit is set by the number it has today: in 1.0 it
     * meant nothing, and a host must not take it as the announcement 1.15 introduced. */
#if defined(CADR_TRAIT_FRAME_SLOTS)
    technique.provides = CADR_TRAIT_FRAME_SLOTS;
#else
    technique.provides = (CadrTraitBits)1 << 10;
#endif
#if defined(CADR_FIXTURE_NEWER_MINOR)
    newer.added_by_the_next_minor = 0xffffffffffffffffu;
    technique.size = sizeof newer;
    memset(&offered, 0, sizeof offered);
    offered.header.size = sizeof offered;
    offered.header.kind = FIXTURE_EXTENSION_KIND;
    offered.value = 42;
    technique.extensions = &offered.header;
#if defined(CADR_FIXTURE_REQUIRES_UNKNOWN)
    technique.required_extensions = required;
    technique.required_extension_count = 1;
#endif
#endif
    memset(&filled, 0, sizeof filled);
    filled.size = sizeof filled;
    filled.abi_major = CADR_PLUGIN_ABI_MAJOR;
    filled.abi_minor = FIXTURE_ABI_MINOR;
    filled.name = "cadr C example";
    filled.technique_count = 1;
    filled.techniques = &technique;
    room = library->size < sizeof filled ? library->size : sizeof filled;
    memcpy(library, &filled, room);
    library->size = (uint32_t)room;
    return CADR_STATUS_OK;
}
