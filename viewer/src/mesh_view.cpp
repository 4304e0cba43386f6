#include "tachi/viewer/controls.hpp"
#include "tachi/viewer/mesh_file.hpp"
#include "tachi/viewer/node.hpp"
#include "tachi/viewer/outputs.hpp"

#include <spdlog/spdlog.h>

#include <set>
#include <stdexcept>

namespace tachi::viewer {
namespace {
Mesh read_mesh(const std::string& path) {
  std::string error;
  auto mesh = read_obj(path, error);
  if (!mesh) throw std::runtime_error("--mesh: " + error);
  return std::move(*mesh);
}

Scene mesh_scene(const std::string& path) {
  Scene scene;
  scene.mesh = read_mesh(path);
  const std::set<std::uint16_t> groups(scene.mesh.groups.begin(), scene.mesh.groups.end());
  scene.status = path + ": " + std::to_string(scene.mesh.triangles.size()) + " triangles, " + std::to_string(groups.size()) +
                 (groups.size() == 1 ? " piece" : " pieces");
  return scene;
}

View framed(const Scene& scene, int size, ViewerWindow* display) {
  View view;
  view.width = view.height = size;
  if (display) {
    const cv::Size shown = display->image_size();
    view.width = shown.width;
    view.height = shown.height;
  }
  return framing(scene.mesh, view);
}

ViewerOptions snapshot_dir_only(const ViewerOptions& o) {
  ViewerOptions only;  // the `p` key's snapshots; --mesh excludes --video and --frames-dir
  only.snapshot_dir = o.snapshot_dir;
  return only;
}
}  // namespace

struct MeshView::Impl {
  Impl(const ViewerOptions& o, ViewerWindow* display_)
      : options(o), display(display_), scene(mesh_scene(o.mesh)), view(framed(scene, o.size, display)), home(view),
        no_outputs(snapshot_dir_only(o)), outputs(no_outputs, cv::Size(view.width, view.height)), mouse(false),
        start(Clock::now()) {}

  bool spin_once() {
    if (!display) return false;  // headless: the snapshot, written by finish(), is all there is
    const cv::Size size = display->image_size();
    view.width = size.width;
    view.height = size.height;
    image = render(scene, view);
    outputs.frame(image, Clock::now());
    display->show(image);
    const int key = display->poll(static_cast<int>(1000.0 / options.fps));
    if (!display->open()) return false;
    switch (on_key(key, view, home)) {
      case KeyAction::Quit: return false;
      case KeyAction::Snapshot: outputs.snapshot_now(); break;
      case KeyAction::ToggleHelp: scene.show_help = !scene.show_help; break;
      default: break;
    }
    for (const auto& event : display->take_mouse_events()) mouse.on_event(event, scene.mesh, view);
    return !RunLimits{options.duration_s, 0.0}.over(Clock::now() - start, 0, {});
  }

  int finish() {
    if (options.snapshot.empty()) {
      if (!display) spdlog::warn("tachi-viewer: --mesh --headless without --snapshot: nothing will be written");
      return common::kExitOk;
    }
    if (image.empty()) image = render(scene, view);
    write_image(options.snapshot, image);
    return common::kExitOk;
  }

  const ViewerOptions& options;
  ViewerWindow* display;
  Scene scene;
  View view;
  View home;
  ViewerOptions no_outputs;
  Outputs outputs;
  MouseControl mouse;
  Clock::time_point start;
  cv::Mat image;
};

MeshView::MeshView(const ViewerOptions& options, ViewerWindow* display) : impl_(std::make_unique<Impl>(options, display)) {}
MeshView::~MeshView() = default;
bool MeshView::spin_once() { return impl_->spin_once(); }
int MeshView::finish() { return impl_->finish(); }

}  // namespace tachi::viewer
