// tachi-viewer as stages: ViewerNode (the cloth, hands, cuts and objects from the DDS bus, drawn into a window
// or headless into files, with seed 001's mouse blade publishing strokes) and MeshView (an exported mesh,
// offline). The window is the executable's (OpenCV highgui, viewer/window.cpp) behind `ViewerWindow`, so the nodes
// run headless in tests; the process is a deployment choice: viewer/main.cpp only parses flags.
// ViewerNode links from tachi_viewer_node (DDS); MeshView is pure tachi_viewer.
#pragma once

#include "tachi/viewer/live_policies.hpp"
#include "tachi/viewer/options.hpp"
#include "tachi/viewer/render.hpp"

#include <memory>
#include <string>
#include <vector>

namespace tachi::bus {
class Participant;
}

namespace tachi::viewer {

/// A window: images out, keys and mouse events in.
class ViewerWindow {
 public:
  virtual ~ViewerWindow() = default;
  /// The size to render at (the user may resize the window).
  [[nodiscard]] virtual cv::Size image_size() const = 0;
  virtual void show(const cv::Mat& image) = 0;
  /// Pumps events for up to `wait_ms`; the key pressed (cv::waitKeyEx code) or -1.
  virtual int poll(int wait_ms) = 0;
  virtual std::vector<MouseEvent> take_mouse_events() = 0;
  /// False once the user closed it.
  [[nodiscard]] virtual bool open() const = 0;
  /// The mouse blade is drawn at the cursor instead of the system pointer (seed 001).
  virtual void hide_pointer() = 0;
};

/// The DDS identity the viewer joins as: the mouse blade publishes strokes, which the viewer's own grant
/// does not allow, so with --mouse the default identity "viewer" becomes "mouse" (scripts/make_test_pki.sh).
std::string participant_identity(const ViewerOptions& options);

class ViewerNode {
 public:
  /// Joins `dds` (which must outlive the node); draws into `display` (and takes its keys and mouse), or
  /// headless when it is null. Throws naming the flag when an output cannot be opened.
  ViewerNode(const ViewerOptions& options, bus::Participant& dds, ViewerWindow* display);
  ~ViewerNode();
  ViewerNode(const ViewerNode&) = delete;
  ViewerNode& operator=(const ViewerNode&) = delete;

  /// Waits (100 ms at most) for input, takes it into the scene, renders a frame when one is due. False when
  /// the run is over: q, the window closed, --duration, or --exit-when-idle.
  bool spin_once();
  /// Closes a stroke the mouse blade still holds, writes --snapshot and the video; the exit code.
  int finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The offline view of an exported OBJ (--mesh; pieces in shades): in `display` until q or --duration, or
/// headless (null) straight to --snapshot. Throws naming --mesh when the file cannot be read.
class MeshView {
 public:
  MeshView(const ViewerOptions& options, ViewerWindow* display);
  ~MeshView();
  MeshView(const MeshView&) = delete;
  MeshView& operator=(const MeshView&) = delete;
  bool spin_once();
  int finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tachi::viewer
