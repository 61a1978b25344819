/* qt_viewer: a host shaped like a CAD tool, in Qt 6 Widgets. A main window with the model tree
 * (a QTreeWidget over the scene graph, read through the C API and filled as its branches are
 * opened) beside the 3D view (a QWindow whose Vulkan surface cadr presents into, with cadr's
 * own swapchain), a toolbar with the display modes and a section. A click in the view picks
 * the part under the cursor and selects its node in the tree; selecting a node in the tree
 * highlights it in the view.
 *
 *   qt_viewer [scene] [--self-test DIR]      (default gen:demo; X11 through xcb)
 *
 * --self-test drives the window as a user would (a pick, a tree selection, the display modes,
 * the section), renders the same view offscreen into DIR/offscreen.png, prints
 * "screenshot ready WxH at X,Y" (the view's place on the screen), keeps the window until a
 * line arrives on standard input, then prints the validation errors and quits. */
#include "cadr.h"

#define VK_USE_PLATFORM_XCB_KHR
#include <vulkan/vulkan.h>

#include <QApplication>
#include <QCheckBox>
#include <QComboBox>
#include <QExposeEvent>
#include <QGuiApplication>
#include <QHBoxLayout>
#include <QHash>
#include <QMainWindow>
#include <QMouseEvent>
#include <QPlatformSurfaceEvent>
#include <QSplitter>
#include <QTimer>
#include <QToolBar>
#include <QTreeWidget>
#include <QVulkanInstance>
#include <QWindow>
#include <QtGui/qguiapplication_platform.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

namespace {

/* Stops with the call, its result and cadr's message when a call fails. */
void check(CadrResult result, const char *call) {
  if (result == CADR_RESULT_OK) {
    return;
  }
  char message[1024] = "";
  size_t length = 0;
  cadr_last_error_message(message, sizeof message, &length);
  std::fprintf(stderr, "qt_viewer: %s failed: %s (%s)\n", call, cadr_result_string(result),
               message);
  std::exit(1);
}
#define CHECK(call) check((call), #call)

/* A node's name, or its kind when it has none. */
QString nodeLabel(CadrScene scene, CadrNode node) {
  static const char *const kinds[] = {"Group", "Transform", "Geo", "Switch", "Lod", "Billboard"};
  size_t length = 0;
  std::string name;
  if (cadr_scene_node_name(scene, node, nullptr, 0, &length) == CADR_RESULT_BUFFER_TOO_SMALL) {
    name.resize(length);
    CHECK(cadr_scene_node_name(scene, node, name.data(), name.size(), &length));
    name.resize(length);
  }
  CadrNodeKind kind = CADR_NODE_KIND_GROUP;
  CHECK(cadr_scene_node_kind(scene, node, &kind));
  QString label = QString::fromStdString(name);
  return label.isEmpty() ? QString(kinds[kind]) : label + "  (" + kinds[kind] + ")";
}

std::vector<CadrNode> childrenOf(CadrScene scene, CadrNode node) {
  uint32_t count = 0;
  CHECK(cadr_scene_child_count(scene, node, &count));
  std::vector<CadrNode> children(count);
  for (uint32_t i = 0; i < count; ++i) {
    CHECK(cadr_scene_child(scene, node, i, &children[i]));
  }
  return children;
}

/* The 3D view: a native window cadr presents into. */
class CadrView : public QWindow {
  Q_OBJECT

public:
  CadrView(CadrContext context, CadrScene scene, QVulkanInstance *vulkan)
      : context_(context), scene_(scene) {
    setSurfaceType(QSurface::VulkanSurface);
    setVulkanInstance(vulkan);
    CHECK(cadr_scene_bounds(scene, &bounds_));
  }
  ~CadrView() override { releaseRenderer(); }

  CadrRenderer renderer() const { return renderer_; }

  /* The camera of the view at its size: the scene fitted, seen from cadr's default direction
   * (front-right, above). */
  CadrCamera camera() const {
    CadrCamera camera;
    CHECK(cadr_camera_fit(&bounds_, double(width()) / std::max(1, height()), nullptr, &camera));
    return camera;
  }

  void setShadeMode(uint32_t mode) {
    shade_ = mode;
    applyShadeMode();
    render();
  }

  /* A section through the middle of the scene, across x, with caps; or none. */
  void setSection(bool on) {
    section_ = on;
    applySection();
    render();
  }

  /* Highlights `node` (0: nothing), clearing the last one. */
  void highlight(CadrNode node) {
    setHighlighted(highlighted_, false);
    highlighted_ = node;
    setHighlighted(highlighted_, true);
    render();
  }

  /* Draws a frame now, if the window can show one. */
  void render() {
    if (renderer_ == nullptr || !isExposed()) {
      return;
    }
    CadrCamera view = camera();
    CHECK(cadr_renderer_render(renderer_, scene_, &view, nullptr));
    ++frames_;
  }

  unsigned frames() const { return frames_; }

  /* Picks at (x, y) of the view and says which node is there (0: none). */
  CadrNode pickAt(int x, int y) {
    if (renderer_ == nullptr || x < 0 || y < 0 || x >= width() || y >= height()) {
      return 0;
    }
    CadrCamera view = camera();
    CadrPickResult result = {};
    result.size = sizeof result;
    CHECK(cadr_renderer_pick(renderer_, scene_, &view, uint32_t(x), uint32_t(y), &result));
    CadrNode node = result.hit_count > 0 ? result.hits[0].node : 0;
    cadr_pick_result_free(&result);
    emit picked(node);
    return node;
  }

signals:
  void picked(CadrNode node);

protected:
  void exposeEvent(QExposeEvent *) override {
    if (isExposed()) {
      ensureRenderer();
      render();
    }
  }

  void resizeEvent(QResizeEvent *) override {
    if (renderer_ != nullptr && width() > 0 && height() > 0) {
      CHECK(cadr_renderer_resize(renderer_, uint32_t(width()), uint32_t(height())));
      render();
    }
  }

  void mousePressEvent(QMouseEvent *event) override {
    if (event->button() == Qt::LeftButton) {
      QPoint at = event->position().toPoint();
      pickAt(at.x(), at.y());
    }
  }

  bool event(QEvent *event) override {
    /* The native window goes: the swapchain and surface must go first. */
    if (event->type() == QEvent::PlatformSurface &&
        static_cast<QPlatformSurfaceEvent *>(event)->surfaceEventType() ==
            QPlatformSurfaceEvent::SurfaceAboutToBeDestroyed) {
      releaseRenderer();
    }
    return QWindow::event(event);
  }

private:
  /* Makes the surface of the native window (X11 through xcb) and cadr's renderer for it. */
  void ensureRenderer() {
    if (renderer_ != nullptr) {
      return;
    }
    auto *x11 = qGuiApp->nativeInterface<QNativeInterface::QX11Application>();
    if (x11 == nullptr) {
      std::fprintf(stderr, "qt_viewer: the view needs X11 (QT_QPA_PLATFORM=xcb)\n");
      std::exit(1);
    }
    auto create = reinterpret_cast<PFN_vkCreateXcbSurfaceKHR>(
        vulkanInstance()->getInstanceProcAddr("vkCreateXcbSurfaceKHR"));
    VkXcbSurfaceCreateInfoKHR info = {};
    info.sType = VK_STRUCTURE_TYPE_XCB_SURFACE_CREATE_INFO_KHR;
    info.connection = x11->connection();
    info.window = xcb_window_t(winId());
    VkSurfaceKHR surface = VK_NULL_HANDLE;
    if (create == nullptr ||
        create(vulkanInstance()->vkInstance(), &info, nullptr, &surface) != VK_SUCCESS) {
      std::fprintf(stderr, "qt_viewer: cannot create a Vulkan surface for the view\n");
      std::exit(1);
    }
    /* The renderer owns the surface from here on. */
    CHECK(cadr_renderer_create_for_surface(context_, uint64_t(surface), uint32_t(width()),
                                           uint32_t(height()), &renderer_));
    applyShadeMode();
    applySection();
  }

  void releaseRenderer() {
    if (renderer_ != nullptr) {
      CHECK(cadr_renderer_destroy(renderer_));
      renderer_ = nullptr;
    }
  }

  /* Settings are one struct: the renderer's, with the display mode changed. */
  void applyShadeMode() {
    if (renderer_ == nullptr) {
      return;
    }
    CadrRendererSettings settings = {};
    settings.size = sizeof settings;
    CHECK(cadr_renderer_settings(renderer_, &settings));
    settings.shade_mode = shade_;
    CHECK(cadr_renderer_apply_settings(renderer_, &settings));
  }

  void applySection() {
    if (renderer_ == nullptr) {
      return;
    }
    if (!section_) {
      CHECK(cadr_renderer_set_section_planes(renderer_, nullptr, 0));
      return;
    }
    const double plane[4] = {-1.0, 0.0, 0.0, 0.5 * (bounds_.min[0] + bounds_.max[0])};
    /* Caps are on by default (CadrRendererSettings::section_flags). */
    CHECK(cadr_renderer_set_section_planes(renderer_, plane, 1));
  }

  void setHighlighted(CadrNode node, bool on) {
    if (node == 0) {
      return;
    }
    uint32_t flags = 0;
    CHECK(cadr_scene_flags(scene_, node, &flags));
    flags = on ? flags | CADR_NODE_HIGHLIGHTED : flags & ~uint32_t(CADR_NODE_HIGHLIGHTED);
    CHECK(cadr_scene_set_flags(scene_, node, flags));
  }

  CadrContext context_;
  CadrScene scene_;
  CadrRenderer renderer_ = nullptr;
  CadrBounds bounds_ = {};
  uint32_t shade_ = CADR_SHADE_SOLID;
  bool section_ = false;
  CadrNode highlighted_ = 0;
  unsigned frames_ = 0;
};

/* Which node a tree item shows. */
constexpr int NodeRole = Qt::UserRole;
/* Whether a tree item's children were read from the scene. */
constexpr int FilledRole = Qt::UserRole + 1;

/* The main window: the model tree beside the view, and the toolbar. */
class MainWindow : public QMainWindow {
  Q_OBJECT

public:
  MainWindow(CadrContext context, CadrScene scene, QVulkanInstance *vulkan)
      : scene_(scene), view_(new CadrView(context, scene, vulkan)) {
    setWindowTitle("cadr — Qt viewer");
    auto *toolbar = addToolBar("view");
    shade_ = new QComboBox(toolbar);
    shade_->addItems({"Solid", "Edges", "Hidden line", "Wireframe", "X-ray"});
    toolbar->addWidget(shade_);
    section_ = new QCheckBox("Section", toolbar);
    toolbar->addWidget(section_);
    tree_ = new QTreeWidget;
    tree_->setHeaderLabel("Model");
    auto *splitter = new QSplitter;
    splitter->addWidget(tree_);
    container_ = QWidget::createWindowContainer(view_, splitter);
    container_->setMinimumSize(160, 120);
    splitter->addWidget(container_);
    splitter->setSizes({240, 640});
    setCentralWidget(splitter);

    CadrNode root = 0;
    CHECK(cadr_scene_root(scene, &root));
    addItem(tree_->invisibleRootItem(), root)->setExpanded(true);
    connect(tree_, &QTreeWidget::itemExpanded, this, [this](QTreeWidgetItem *item) { fill(item); });
    connect(tree_, &QTreeWidget::itemSelectionChanged, this, [this] {
      QList<QTreeWidgetItem *> selected = tree_->selectedItems();
      view_->highlight(selected.isEmpty() ? 0 : selected[0]->data(0, NodeRole).toULongLong());
    });
    connect(view_, &CadrView::picked, this, [this](CadrNode node) { select(node); });
    connect(shade_, &QComboBox::currentIndexChanged, this,
            [this](int index) { view_->setShadeMode(uint32_t(index)); });
    connect(section_, &QCheckBox::toggled, this, [this](bool on) { view_->setSection(on); });
  }

  CadrView *view() const { return view_; }
  QWidget *viewWidget() const { return container_; }
  QTreeWidget *tree() const { return tree_; }
  QComboBox *shadeBox() const { return shade_; }
  QCheckBox *sectionBox() const { return section_; }

  /* Selects the first place of `node` in the tree (opening the branches above it), or clears
   * the selection for 0. */
  void select(CadrNode node) {
    if (node == 0) {
      tree_->clearSelection();
      return;
    }
    std::vector<CadrNode> path;
    CadrNode root = 0;
    CHECK(cadr_scene_root(scene_, &root));
    QHash<CadrNode, bool> seen;
    if (!findPath(root, node, path, seen)) {
      return;
    }
    QTreeWidgetItem *item = tree_->topLevelItem(0);
    for (size_t depth = 1; depth < path.size() && item != nullptr; ++depth) {
      fill(item);
      item->setExpanded(true);
      QTreeWidgetItem *next = nullptr;
      for (int i = 0; i < item->childCount() && next == nullptr; ++i) {
        if (item->child(i)->data(0, NodeRole).toULongLong() == path[depth]) {
          next = item->child(i);
        }
      }
      item = next;
    }
    if (item != nullptr) {
      tree_->setCurrentItem(item);
      tree_->scrollToItem(item);
    }
  }

private:
  /* A tree item for `node` under `parent`, with a placeholder child when it has children. */
  QTreeWidgetItem *addItem(QTreeWidgetItem *parent, CadrNode node) {
    auto *item = new QTreeWidgetItem(parent, {nodeLabel(scene_, node)});
    item->setData(0, NodeRole, QVariant::fromValue<qulonglong>(node));
    item->setData(0, FilledRole, false);
    uint32_t count = 0;
    CHECK(cadr_scene_child_count(scene_, node, &count));
    item->setChildIndicatorPolicy(count > 0 ? QTreeWidgetItem::ShowIndicator
                                            : QTreeWidgetItem::DontShowIndicator);
    return item;
  }

  /* Reads an item's children from the scene, once. */
  void fill(QTreeWidgetItem *item) {
    if (item->data(0, FilledRole).toBool()) {
      return;
    }
    item->setData(0, FilledRole, true);
    for (CadrNode child : childrenOf(scene_, item->data(0, NodeRole).toULongLong())) {
      addItem(item, child);
    }
  }

  /* The first path from `from` down to `target` (shared subgraphs are searched once). */
  bool findPath(CadrNode from, CadrNode target, std::vector<CadrNode> &path,
                QHash<CadrNode, bool> &seen) {
    path.push_back(from);
    if (from == target) {
      return true;
    }
    if (!seen.contains(from)) {
      seen.insert(from, true);
      for (CadrNode child : childrenOf(scene_, from)) {
        if (findPath(child, target, path, seen)) {
          return true;
        }
      }
    }
    path.pop_back();
    return false;
  }

  CadrScene scene_;
  CadrView *view_;
  QWidget *container_ = nullptr;
  QTreeWidget *tree_ = nullptr;
  QComboBox *shade_ = nullptr;
  QCheckBox *section_ = nullptr;
};

/* Lets Qt deliver what is queued (expose, resize, selection) and the view draw. */
void settle() {
  for (int i = 0; i < 20; ++i) {
    QCoreApplication::processEvents(QEventLoop::AllEvents, 20);
  }
}

/* The self-test: a user's session in a few steps, each checked and printed. */
int selfTest(MainWindow &window, CadrContext context, CadrScene scene, const std::string &dir) {
  CadrView *view = window.view();
  for (int i = 0; i < 100 && view->frames() == 0; ++i) {
    settle();
  }
  if (view->frames() == 0) {
    std::fprintf(stderr, "qt_viewer: the view never showed a frame\n");
    return 1;
  }
  std::printf("rendered %u frames\n", view->frames());

  /* A click in the middle of the view selects the picked node in the tree. */
  CadrNode picked = view->pickAt(view->width() / 2, view->height() / 2);
  settle();
  QTreeWidgetItem *current = window.tree()->currentItem();
  if (picked == 0 || current == nullptr || current->data(0, NodeRole).toULongLong() != picked) {
    std::fprintf(stderr, "qt_viewer: the pick did not select its node in the tree\n");
    return 1;
  }
  std::printf("picked node %llu, tree selected %s\n", (unsigned long long)picked,
              current->text(0).toStdString().c_str());
  uint32_t flags = 0;
  CHECK(cadr_scene_flags(scene, picked, &flags));
  std::printf("highlighted in the view: %s\n", (flags & CADR_NODE_HIGHLIGHTED) ? "yes" : "no");

  /* The display modes and the section, from the toolbar. */
  static const char *const modes[] = {"solid", "edges", "hidden-line", "wireframe", "xray"};
  for (int mode = 1; mode <= 5; ++mode) {
    window.shadeBox()->setCurrentIndex(mode % 5);
    settle();
    std::printf("display mode: %s\n", modes[mode % 5]);
  }
  window.sectionBox()->setChecked(true);
  settle();
  std::printf("section: on\n");
  window.sectionBox()->setChecked(false);
  settle();
  std::printf("section: off\n");

  /* Clearing the selection clears the highlight. */
  window.tree()->clearSelection();
  settle();
  CHECK(cadr_scene_flags(scene, picked, &flags));
  std::printf("highlighted after clearing: %s\n", (flags & CADR_NODE_HIGHLIGHTED) ? "yes" : "no");

  /* The same view offscreen, for the test to compare with a grab of the window. */
  CadrRenderer offscreen = nullptr;
  CadrCamera camera = view->camera();
  uint32_t width = uint32_t(view->width()), height = uint32_t(view->height());
  CHECK(cadr_renderer_create(context, width, height, &offscreen));
  CHECK(cadr_renderer_render(offscreen, scene, &camera, nullptr));
  CHECK(cadr_renderer_save_png(offscreen, (dir + "/offscreen.png").c_str()));
  CHECK(cadr_renderer_destroy(offscreen));
  view->render();
  settle();
  QPoint at = window.viewWidget()->mapToGlobal(QPoint(0, 0));
  std::printf("screenshot ready %ux%u at %d,%d\n", width, height, at.x(), at.y());
  std::fflush(stdout);
  std::string line;
  std::getline(std::cin, line);
  uint64_t errors = 0;
  CHECK(cadr_context_validation_error_count(context, &errors));
  std::printf("validation errors: %llu\n", (unsigned long long)errors);
  return errors == 0 ? 0 : 1;
}

} // namespace

int main(int argc, char **argv) {
  /* The view presents through an X11 surface. */
  if (qEnvironmentVariableIsEmpty("QT_QPA_PLATFORM")) {
    qputenv("QT_QPA_PLATFORM", "xcb");
  }
  QApplication application(argc, argv);
  std::string source = "gen:demo", test_dir;
  for (int i = 1; i < argc; ++i) {
    std::string argument = argv[i];
    if (argument == "--self-test" && i + 1 < argc) {
      test_dir = argv[++i];
    } else if (!argument.empty() && argument[0] == '-') {
      std::fprintf(stderr, "qt_viewer: unknown option %s\n", argument.c_str());
      return 2;
    } else {
      source = argument;
    }
  }

  /* cadr's context with the instance extensions of an X11 window. */
  const char *extensions[] = {"VK_KHR_surface", "VK_KHR_xcb_surface"};
  CadrContextOptions options = {};
  options.size = sizeof options;
  CHECK(cadr_context_options_default(&options));
  options.instance_extensions = extensions;
  options.instance_extension_count = 2;
  options.validation = !test_dir.empty();
  CadrContext context = nullptr;
  CHECK(cadr_context_create(&options, &context));
  void *instance = nullptr;
  CHECK(cadr_context_vulkan_instance(context, &instance));
  /* Qt's view of cadr's instance: the window needs one, and it lends vkGetInstanceProcAddr. */
  QVulkanInstance vulkan;
  vulkan.setVkInstance(static_cast<VkInstance>(instance));
  if (!vulkan.create()) {
    std::fprintf(stderr, "qt_viewer: Qt cannot use the Vulkan instance\n");
    return 1;
  }

  CadrScene scene = nullptr;
  CadrNode root = 0;
  CHECK(cadr_scene_create(&scene));
  CHECK(cadr_scene_root(scene, &root));
  CadrLoadResult loaded = {};
  loaded.size = sizeof loaded;
  CHECK(cadr_scene_load(scene, source.c_str(), root, &loaded));
  cadr_load_result_free(&loaded);

  int status = 0;
  {
    MainWindow window(context, scene, &vulkan);
    window.resize(900, 600);
    window.move(0, 0);
    window.show();
    status = test_dir.empty() ? application.exec() : selfTest(window, context, scene, test_dir);
  }
  CHECK(cadr_scene_destroy(scene));
  CHECK(cadr_context_destroy(context));
  return status;
}

#include "qt_viewer.moc"
