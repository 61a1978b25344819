// A C++ host of the installed cadr: RAII wrappers over the C handles, a scene built from
// arrays plus a generated one, a frame rendered offscreen and saved.
//   consumer OUTPUT.png
#include <cadr.h>

#include <array>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

void check(CadrResult result, const char* what) {
  if (result != CADR_RESULT_OK) {
    std::size_t length = 0;
    std::vector<char> message(4096);
    cadr_last_error_message(message.data(), message.size(), &length);
    throw std::runtime_error(std::string(what) + ": " + cadr_result_string(result) + ": " +
                             message.data());
  }
}

template <typename Handle, CadrResult (*Destroy)(Handle)>
class Owned {
 public:
  Owned() = default;
  Owned(const Owned&) = delete;
  Owned& operator=(const Owned&) = delete;
  ~Owned() { Destroy(handle_); }
  Handle* out() { return &handle_; }
  Handle get() const { return handle_; }

 private:
  Handle handle_ = nullptr;
};

using Context = Owned<CadrContext, cadr_context_destroy>;
using Scene = Owned<CadrScene, cadr_scene_destroy>;
using Renderer = Owned<CadrRenderer, cadr_renderer_destroy>;

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: consumer OUTPUT.png\n");
    return 2;
  }
  try {
    std::uint32_t major = 0, minor = 0, patch = 0;
    cadr_version(&major, &minor, &patch);
    if (major != CADR_VERSION_MAJOR || minor != CADR_VERSION_MINOR) {
      throw std::runtime_error("header and library versions differ");
    }
    // Every struct that crosses the API starts with its size (see cadr.h, Versions).
    CadrContextOptions options{};
    options.size = sizeof options;
    check(cadr_context_options_default(&options), "options");
#ifdef CADR_PLUGIN_DIR
    // Linked statically: no libcadr.so to find the plugins beside, so name their directory.
    const char* dirs[] = {CADR_PLUGIN_DIR};
    options.plugin_dirs = dirs;
    options.plugin_dir_count = 1;
#endif
    Context context;
    check(cadr_context_create(&options, context.out()), "context");
    Scene scene;
    check(cadr_scene_create(scene.out()), "scene");
    CadrNode root = 0;
    check(cadr_scene_root(scene.get(), &root), "root");

    // A tetrahedron from arrays, placed twice (shared geometry).
    const std::array<float, 12> positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    const std::array<std::uint32_t, 12> indices = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
    CadrGeometryDesc desc{};
    desc.size = sizeof desc;
    desc.name = "tetrahedron";
    desc.positions = positions.data();
    desc.vertex_count = 4;
    desc.indices = indices.data();
    desc.index_count = static_cast<std::uint32_t>(indices.size());
    CadrGeometry tetrahedron = 0;
    check(cadr_scene_create_geometry(scene.get(), &desc, &tetrahedron), "geometry");
    CadrMaterialDesc orange{sizeof(CadrMaterialDesc), "orange", {0.9f, 0.45f, 0.1f, 1.0f}, 0.0f, 0.5f};
    CadrMaterial material = 0;
    check(cadr_scene_create_material(scene.get(), &orange, &material), "material");
    for (int i = 0; i < 2; ++i) {
      std::array<double, 16> matrix = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 1.5 * i, 0, 0, 1};
      CadrNode place = 0, geo = 0;
      check(cadr_scene_create_transform(scene.get(), "place", matrix.data(), &place), "transform");
      check(cadr_scene_create_geo(scene.get(), "tetra", tetrahedron, &material, 1, &geo), "geo");
      check(cadr_scene_add_child(scene.get(), place, geo), "add geo");
      check(cadr_scene_add_child(scene.get(), root, place), "add place");
    }
    CadrLoadResult loaded{};
    loaded.size = sizeof loaded;
    check(cadr_scene_load(scene.get(), "gen:grid:parts=30", root, &loaded), "load");
    cadr_load_result_free(&loaded);

    CadrSceneStatistics statistics{};
    statistics.size = sizeof statistics;
    check(cadr_scene_statistics(scene.get(), &statistics), "statistics");
    CadrBounds bounds{};
    check(cadr_scene_bounds(scene.get(), &bounds), "bounds");
    Renderer renderer;
    check(cadr_renderer_create(context.get(), 320, 240, renderer.out()), "renderer");
    CadrCamera camera{};
    check(cadr_camera_fit(&bounds, 320.0 / 240.0, nullptr, &camera), "camera");
    CadrFrameStats stats{};
    stats.size = sizeof stats;
    check(cadr_renderer_render(renderer.get(), scene.get(), &camera, &stats), "render");
    check(cadr_renderer_save_png(renderer.get(), argv[1]), "save");
    const char* submission = nullptr;
    check(cadr_renderer_technique(renderer.get(), CADR_TECHNIQUE_KIND_SUBMISSION, &submission),
          "technique");
    std::printf("consumer: cadr %s, %llu parts shown, %llu of %llu triangles drawn with %s -> %s\n",
                cadr_version_string(), static_cast<unsigned long long>(statistics.visible_instances),
                static_cast<unsigned long long>(stats.triangles),
                static_cast<unsigned long long>(statistics.visible_triangles), submission, argv[1]);
    // Everything is in view: every shown triangle is drawn.
    return stats.triangles == statistics.visible_triangles ? 0 : 1;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "consumer: %s\n", error.what());
    return 1;
  }
}
