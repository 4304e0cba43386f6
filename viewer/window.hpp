// The viewer's window (OpenCV highgui): resizable, sized to fit the screen it opens on, without
// the Qt toolbar Debian's highgui adds by default (FIELD_NOTES), with its mouse events queued for
// the main loop. Rendering stays in the pure renderer: the window only shows images.
#pragma once

#include "tachi/viewer/node.hpp"

#include <opencv2/core.hpp>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace tachi::viewer {

/// Width and height of the X screen the window opens on, or nothing without an X display.
std::optional<cv::Size> screen_size();

/// The window tachi-viewer opens (named "tachi", --size pixels), or none with --headless. Throws when a
/// window is asked for without an X display.
std::unique_ptr<ViewerWindow> open_window(const ViewerOptions& options);

class Window final : public ViewerWindow {
 public:
  /// Opens a window of `requested` pixels, shrunk to fit the screen (with room for the title bar).
  Window(std::string name, cv::Size requested);
  ~Window() override;
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;

  /// The size to render at: the window's current image area (the user may resize it).
  cv::Size image_size() const override;
  void show(const cv::Mat& image) override;
  /// Pumps the window's events for up to `wait_ms`; returns the key pressed (cv::waitKeyEx code) or -1.
  int poll(int wait_ms) override;
  /// Mouse events since the last call.
  std::vector<MouseEvent> take_mouse_events() override;
  /// False once the user closed the window.
  bool open() const override;
  /// Hides the system pointer over the window (seed 001: the blade image drawn at the cursor replaces
  /// it). Applied as soon as the window is mapped.
  void hide_pointer() override { hide_pointer_ = true; }

 private:
  static void on_mouse(int event, int x, int y, int flags, void* self);
  void apply_hidden_pointer();
  /// The size that fits the screen (the requested one where the screen is large enough); nullopt while
  /// the screen does not answer.
  std::optional<cv::Size> fitted() const;
  void settle_fit();
  std::string name_;
  cv::Size requested_;
  bool screen_known_ = false;
  bool fit_settled_ = false;  ///< the window was seen at the fitted size (from then on the user's to resize)
  int fit_checks_ = 0;
  void* display_ = nullptr;  ///< Xlib Display*, kept open while the blank cursor is in use
  bool hide_pointer_ = false;
  bool pointer_hidden_ = false;
  int pointer_attempts_ = 0;
  cv::Size size_;
  std::vector<MouseEvent> events_;
};

}  // namespace tachi::viewer
