/* soak: a C host that does, over and over, what a CAD tool does all day through the C API --
 * loads a file into the scene, edits it (moves, hides and shows parts), renders, picks, swaps
 * technique plugins, then unloads the file -- and watches its memory: the process's resident
 * size (/proc/self/statm), and the device memory and host memory cadr holds
 * (cadr_context_memory_usage: its host memory is what its own code holds, which the drivers'
 * allocations do not blur).
 *
 *   soak [--scene SCENE] [--load FILE] [--size WxH] [--validation]
 *        [--seconds S | --iterations N] [--warmup-seconds S | --warmup-iterations N]
 *        [--max-growth-percent P] [--csv FILE] [--keep-loaded] [--combinations N]
 *
 * SCENE (default gen:graphicscard) is loaded once and stays; FILE (a .gltf, .glb, .csf or a
 * generator; default gen:demo) is loaded and unloaded every iteration. Memory is sampled once
 * an iteration, at the same point (after the pick, before the unload). After the warm-up, the
 * highest sample of each kind is compared with the highest of the warm-up: the run fails (exit
 * 1) when any of the three grew by more than P percent (default 1). Each sample is a line of
 * FILE (seconds,iteration,resident_bytes,device_allocated_bytes,device_reserved_bytes,
 * heap_in_use_bytes,cadr_host_bytes). The heap in use (glibc's mallinfo2: what is allocated
 * and not freed, by cadr, the drivers and this program) is reported beside the resident size,
 * not judged: where resident memory grows and the heap in use does not, the allocator is
 * keeping memory that was freed, not cadr.
 * `--keep-loaded` never unloads FILE, so that memory grows: the check of the check. The
 * techniques cycle through N valid (submission, culling) pairs (default 8, spread over all the
 * valid ones); the warm-up lasts at least one cycle, so that every pair's pipelines exist
 * before memory is compared.
 *
 * Built with the samples' helpers (samples/common/sample.c: checked calls, matrices, cadr's
 * warnings on stderr). Run by scripts/soak.sh (minutes on gen:graphicscard) and, briefly and
 * with validation, by tests/tests/soak.rs. Exits 1 on a failed call, a validation error or
 * growth past the bound. */
#define _GNU_SOURCE
#include "common/sample.h"

#include <malloc.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

struct Options {
  const char *scene;
  const char *load;
  uint32_t width, height;
  bool validation;
  bool keep_loaded;
  long combinations;
  double seconds, warmup_seconds;
  long iterations, warmup_iterations;
  double max_growth_percent;
  const char *csv;
};

static void usage(const char *why) {
  fprintf(stderr,
          "soak: %s\nusage: soak [--scene SCENE] [--load FILE] [--size WxH] [--validation]\n"
          "            [--seconds S | --iterations N] [--warmup-seconds S | --warmup-iterations N]\n"
          "            [--max-growth-percent P] [--csv FILE] [--keep-loaded] [--combinations N]\n",
          why);
  exit(2);
}

static struct Options parse(int argc, char **argv) {
  struct Options o = {"gen:graphicscard", "gen:demo", 640, 480, false, false, 8, 60.0, 10.0, -1,
                      -1, 1.0, NULL};
  int i;
  for (i = 1; i < argc; ++i) {
    const char *flag = argv[i];
    const char *value = i + 1 < argc ? argv[i + 1] : NULL;
    if (strcmp(flag, "--validation") == 0) {
      o.validation = true;
      continue;
    }
    if (strcmp(flag, "--keep-loaded") == 0) {
      o.keep_loaded = true;
      continue;
    }
    if (value == NULL) {
      usage("an option lacks its value");
    }
    ++i;
    if (strcmp(flag, "--scene") == 0) {
      o.scene = value;
    } else if (strcmp(flag, "--load") == 0) {
      o.load = value;
    } else if (strcmp(flag, "--size") == 0) {
      if (sscanf(value, "%ux%u", &o.width, &o.height) != 2 || o.width == 0 || o.height == 0) {
        usage("--size takes WxH");
      }
    } else if (strcmp(flag, "--seconds") == 0) {
      o.seconds = atof(value);
    } else if (strcmp(flag, "--iterations") == 0) {
      o.iterations = atol(value);
    } else if (strcmp(flag, "--warmup-seconds") == 0) {
      o.warmup_seconds = atof(value);
    } else if (strcmp(flag, "--warmup-iterations") == 0) {
      o.warmup_iterations = atol(value);
    } else if (strcmp(flag, "--max-growth-percent") == 0) {
      o.max_growth_percent = atof(value);
    } else if (strcmp(flag, "--combinations") == 0) {
      o.combinations = atol(value);
      if (o.combinations < 1) {
        usage("--combinations takes a number from 1");
      }
    } else if (strcmp(flag, "--csv") == 0) {
      o.csv = value;
    } else {
      usage("unknown option");
    }
  }
  return o;
}

static double now_seconds(void) {
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return (double)t.tv_sec + (double)t.tv_nsec * 1e-9;
}

/* The process's resident size in bytes. */
static unsigned long long resident_bytes(void) {
  unsigned long long total = 0, resident = 0;
  FILE *statm = fopen("/proc/self/statm", "r");
  if (statm == NULL || fscanf(statm, "%llu %llu", &total, &resident) != 2) {
    fprintf(stderr, "soak: /proc/self/statm cannot be read\n");
    exit(1);
  }
  fclose(statm);
  return resident * (unsigned long long)sysconf(_SC_PAGESIZE);
}

/* The supported techniques of `kind`, at most `capacity` names (the context owns them). */
static size_t supported(CadrContext context, enum CadrTechniqueKind kind, const char **names,
                        size_t capacity) {
  uint32_t count = 0, i;
  size_t found = 0;
  CADR_CHECK(cadr_context_technique_count(context, &count));
  for (i = 0; i < count && found < capacity; ++i) {
    struct CadrTechniqueInfo info = {.size = sizeof(struct CadrTechniqueInfo)};
    CADR_CHECK(cadr_context_technique(context, i, &info));
    if (info.kind == kind && info.supported) {
      names[found++] = info.name;
    }
  }
  return found;
}

/* Up to `capacity` valid (submission, culling) selections, spread evenly over all of them, none
 * with the submission `left_out` (NULL: none left out). */
static size_t valid_selections(CadrContext context, CadrRenderer renderer,
                               struct CadrTechniqueSelection *chosen, size_t capacity,
                               const char *left_out) {
  const char *submissions[32], *cullers[32];
  struct CadrTechniqueSelection valid[32 * 32];
  size_t submission_count = supported(context, CADR_TECHNIQUE_KIND_SUBMISSION, submissions, 32);
  size_t culler_count = supported(context, CADR_TECHNIQUE_KIND_CULLING, cullers, 32);
  size_t count = 0, i, j;
  for (i = 0; i < submission_count; ++i) {
    if (left_out != NULL && strcmp(submissions[i], left_out) == 0) {
      continue;
    }
    for (j = 0; j < culler_count; ++j) {
      struct CadrTechniqueSelection selection = {sizeof(struct CadrTechniqueSelection), NULL, NULL, submissions[i], cullers[j]};
      if (cadr_renderer_check_techniques(renderer, &selection) == CADR_RESULT_OK) {
        valid[count++] = selection;
      }
    }
  }
  for (i = 0; i < capacity && i < count; ++i) {
    chosen[i] = valid[i * count / (capacity < count ? capacity : count)];
  }
  return i;
}

/* Bytes the C allocator has handed out and not had back (0 where it cannot say). */
static unsigned long long heap_in_use(void) {
#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 33))
  struct mallinfo2 info = mallinfo2();
  return (unsigned long long)(info.uordblks + info.hblkhd);
#else
  return 0;
#endif
}

struct Extremes {
  unsigned long long resident, device, heap, cadr_host;
};

static double growth_percent(unsigned long long before, unsigned long long after) {
  return before == 0 ? (after == 0 ? 0.0 : INFINITY) : 100.0 * ((double)after / before - 1.0);
}

int main(int argc, char **argv) {
  struct Options o = parse(argc, argv);
  struct CadrContextOptions context_options = {.size = sizeof(struct CadrContextOptions)};
  CadrContext context;
  CadrScene scene;
  CadrRenderer renderer;
  CadrNode root, place;
  struct CadrLoadResult base = {.size = sizeof(struct CadrLoadResult)};
  struct CadrBounds bounds;
  struct CadrDeviceInfo device = {.size = sizeof(struct CadrDeviceInfo)};
  int dgc_left_out;
  struct CadrTechniqueSelection *selections;
  size_t selection_count;
  struct Extremes warm = {0, 0, 0, 0}, after = {0, 0, 0, 0}, last = {0, 0, 0, 0};
  FILE *csv = NULL;
  double start, elapsed = 0.0;
  long iteration = 0, samples_after = 0;
  uint64_t validation_errors = 0;
  double identity[16];

  sample_identity(identity);
  sample_print_messages();
  CADR_CHECK(cadr_context_options_default(&context_options));
  context_options.validation = o.validation;
  CADR_CHECK(cadr_context_create(&context_options, &context));
  CADR_CHECK(cadr_scene_create(&scene));
  CADR_CHECK(cadr_scene_root(scene, &root));
  CADR_CHECK(cadr_scene_load(scene, o.scene, root, &base));
  CADR_CHECK(cadr_scene_create_transform(scene, "soak place", identity, &place));
  CADR_CHECK(cadr_scene_add_child(scene, root, place));
  CADR_CHECK(cadr_scene_bounds(scene, &bounds));
  CADR_CHECK(cadr_renderer_create(context, o.width, o.height, &renderer));
  selections = malloc(sizeof *selections * (size_t)o.combinations);
  if (selections == NULL) {
    fprintf(stderr, "soak: out of memory\n");
    return 1;
  }
  /* Mesa's lavapipe (25.0.7) keeps 40 bytes for every vkCmdExecuteGeneratedCommandsEXT
   * recorded and never frees them (heaptrack: 786 432 such blocks from the execute call over 30
   * iterations on gen:graphicscard, where its preprocess-memory answer forces thousands of small
   * executions a pass): a driver leak that would hide cadr's own figures. */
  CADR_CHECK(cadr_context_device_info(context, &device));
  dgc_left_out = strstr(device.name, "llvmpipe") != NULL;
  selection_count = valid_selections(context, renderer, selections, (size_t)o.combinations,
                                     dgc_left_out ? "dgc" : NULL);
  if (selection_count == 0) {
    fprintf(stderr, "soak: no valid submission and culling techniques\n");
    return 1;
  }
  if (o.csv != NULL) {
    csv = fopen(o.csv, "w");
    if (csv == NULL) {
      fprintf(stderr, "soak: %s cannot be written\n", o.csv);
      return 1;
    }
    fprintf(csv, "seconds,iteration,resident_bytes,device_allocated_bytes,device_reserved_bytes,"
                 "heap_in_use_bytes,cadr_host_bytes\n");
  }
  printf("soak: on %s: %s stays, %s is loaded and unloaded each iteration; %zu technique "
         "combinations swapped in turn; %ux%u%s\n",
         device.name, o.scene, o.load, selection_count, o.width, o.height,
         o.validation ? ", validation on" : "");
  if (dgc_left_out) {
    printf("soak: dgc left out: this lavapipe never frees what it keeps per generated-commands "
           "execution recorded\n");
  }
  fflush(stdout);

  start = now_seconds();
  for (;;) {
    bool warming = (size_t)iteration < selection_count ||
                   (o.warmup_iterations >= 0 ? iteration < o.warmup_iterations
                                             : elapsed < o.warmup_seconds);
    struct CadrLoadResult loaded = {.size = sizeof(struct CadrLoadResult)};
    struct CadrCamera camera;
    struct CadrFrameStats stats = {.size = sizeof(struct CadrFrameStats)};
    struct CadrPickResult picked = {.size = sizeof(struct CadrPickResult)};
    struct CadrMemoryUsage usage = {.size = sizeof(struct CadrMemoryUsage)};
    double angle = 0.37 * (double)iteration, matrix[16];
    const double direction[3] = {cos(angle), sin(angle), 0.6};
    unsigned long long resident, heap;
    size_t i;

    if (o.iterations >= 0 ? iteration >= o.iterations : elapsed >= o.seconds) {
      break;
    }
    /* Load a file under the moving place, and edit: move it, hide and show a part of the
     * scene that stays, highlight another. */
    CADR_CHECK(cadr_scene_load(scene, o.load, place, &loaded));
    sample_translation(matrix, bounds.max[0] * sin(angle), bounds.max[1] * cos(angle), 0.0);
    CADR_CHECK(cadr_scene_set_matrix(scene, place, matrix));
    if (base.node_count > 4) {
      /* A node of the second half (leaves, not the scene's top groups): hidden or highlighted
       * for this iteration, and the one before it back to normal. */
      size_t half = base.node_count / 2;
      CadrNode toggled = base.nodes[half + (size_t)iteration % half];
      CadrNode restored = base.nodes[half + (size_t)(iteration + half - 1) % half];
      CADR_CHECK(cadr_scene_set_flags(scene, restored, CADR_NODE_VISIBLE | CADR_NODE_PICKABLE));
      CADR_CHECK(cadr_scene_set_flags(scene, toggled,
                              iteration % 2 == 0 ? CADR_NODE_PICKABLE
                                                 : CADR_NODE_VISIBLE | CADR_NODE_PICKABLE |
                                                       CADR_NODE_HIGHLIGHTED));
    }
    /* Swap techniques, render from an orbiting camera, pick. */
    CADR_CHECK(
        cadr_renderer_set_techniques(renderer, &selections[(size_t)iteration % selection_count]));
    CADR_CHECK(cadr_scene_bounds(scene, &bounds));
    CADR_CHECK(cadr_camera_fit(&bounds, (double)o.width / o.height, direction, &camera));
    CADR_CHECK(cadr_renderer_render(renderer, scene, &camera, &stats));
    CADR_CHECK(cadr_renderer_pick(renderer, scene, &camera, (uint32_t)(iteration * 7) % o.width,
                          (uint32_t)(iteration * 5) % o.height, &picked));
    cadr_pick_result_free(&picked);

    /* Sample, then unload: the nodes, then the geometries and materials they used. */
    usage.size = sizeof usage;
    CADR_CHECK(cadr_context_memory_usage(context, &usage));
    resident = resident_bytes();
    heap = heap_in_use();
    elapsed = now_seconds() - start;
    if (csv != NULL) {
      fprintf(csv, "%.3f,%ld,%llu,%llu,%llu,%llu,%llu\n", elapsed, iteration, resident,
              (unsigned long long)usage.device_allocated_bytes,
              (unsigned long long)usage.device_reserved_bytes, heap,
              (unsigned long long)usage.host_allocated_bytes);
      fflush(csv);
    }
    last.resident = resident;
    last.device = usage.device_reserved_bytes;
    last.heap = heap;
    last.cadr_host = usage.host_allocated_bytes;
    {
      struct Extremes *phase = warming ? &warm : &after;
      phase->resident = resident > phase->resident ? resident : phase->resident;
      phase->device = last.device > phase->device ? last.device : phase->device;
      phase->heap = heap > phase->heap ? heap : phase->heap;
      phase->cadr_host = last.cadr_host > phase->cadr_host ? last.cadr_host : phase->cadr_host;
    }
    samples_after += warming ? 0 : 1;
    for (i = 0; i < loaded.node_count && !o.keep_loaded; ++i) {
      CADR_CHECK(cadr_scene_destroy_node(scene, loaded.nodes[i]));
    }
    for (i = 0; i < loaded.geometry_count && !o.keep_loaded; ++i) {
      CADR_CHECK(cadr_scene_destroy_geometry(scene, loaded.geometries[i]));
    }
    for (i = 0; i < loaded.material_count && !o.keep_loaded; ++i) {
      CADR_CHECK(cadr_scene_destroy_material(scene, loaded.materials[i]));
    }
    cadr_load_result_free(&loaded);
    ++iteration;
  }
  if (csv != NULL) {
    fclose(csv);
  }
  free(selections);
  CADR_CHECK(cadr_context_validation_error_count(context, &validation_errors));
  cadr_load_result_free(&base);
  CADR_CHECK(cadr_renderer_destroy(renderer));
  CADR_CHECK(cadr_scene_destroy(scene));
  CADR_CHECK(cadr_context_destroy(context));

  printf("soak: %ld iterations in %.1f s (%.2f s each)\n", iteration, elapsed,
         iteration > 0 ? elapsed / (double)iteration : 0.0);
  if (samples_after == 0) {
    fprintf(stderr, "soak: no iteration after the warm-up; run longer\n");
    return 1;
  }
  printf("soak: resident memory: warm-up peak %.1f MiB, later peak %.1f MiB, last %.1f MiB "
         "(%+.2f %%)\n",
         warm.resident / 1048576.0, after.resident / 1048576.0, last.resident / 1048576.0,
         growth_percent(warm.resident, after.resident));
  printf("soak: device memory: warm-up peak %.1f MiB, later peak %.1f MiB, last %.1f MiB "
         "(%+.2f %%)\n",
         warm.device / 1048576.0, after.device / 1048576.0, last.device / 1048576.0,
         growth_percent(warm.device, after.device));
  printf("soak: cadr's own host memory: warm-up peak %.1f MiB, later peak %.1f MiB, last "
         "%.1f MiB (%+.2f %%)\n",
         warm.cadr_host / 1048576.0, after.cadr_host / 1048576.0, last.cadr_host / 1048576.0,
         growth_percent(warm.cadr_host, after.cadr_host));
  printf("soak: heap in use (not judged): warm-up peak %.1f MiB, later peak %.1f MiB, last "
         "%.1f MiB (%+.2f %%)\n",
         warm.heap / 1048576.0, after.heap / 1048576.0, last.heap / 1048576.0,
         growth_percent(warm.heap, after.heap));
  if (validation_errors > 0) {
    fprintf(stderr, "soak: %llu validation errors\n", (unsigned long long)validation_errors);
    return 1;
  }
  if (growth_percent(warm.resident, after.resident) > o.max_growth_percent ||
      growth_percent(warm.device, after.device) > o.max_growth_percent ||
      growth_percent(warm.cadr_host, after.cadr_host) > o.max_growth_percent) {
    fprintf(stderr, "soak: memory grew by more than %.2f %% after the warm-up\n",
            o.max_growth_percent);
    return 1;
  }
  printf("soak: flat within %.2f %% after the warm-up\n", o.max_growth_percent);
  return 0;
}
