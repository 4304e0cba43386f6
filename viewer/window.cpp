#include "window.hpp"

#include <X11/Xlib.h>
#include <opencv2/highgui.hpp>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdlib>
#include <stdexcept>

namespace tachi::viewer {
namespace {
// The X window named `name` under `parent` (the highgui window, or the frame a window manager put
// it in), or 0.
::Window find_window(Display* display, ::Window parent, const std::string& name) {
  char* title = nullptr;
  if (XFetchName(display, parent, &title) != 0 && title != nullptr) {
    const bool match = name == title;
    XFree(title);
    if (match) return parent;
  }
  ::Window root = 0, up = 0, *children = nullptr;
  unsigned count = 0;
  if (XQueryTree(display, parent, &root, &up, &children, &count) == 0) return 0;
  ::Window found = 0;
  for (unsigned i = 0; i < count && found == 0; ++i) found = find_window(display, children[i], name);
  if (children != nullptr) XFree(children);
  return found;
}

// Room left for the window manager's title bar and borders and for a panel/taskbar.
constexpr int kScreenMargin_px = 80;
constexpr int kMinimumSide_px = 64;
}  // namespace

std::optional<cv::Size> screen_size() {
  Display* display = XOpenDisplay(nullptr);
  if (display == nullptr) return std::nullopt;
  const int screen = DefaultScreen(display);
  const cv::Size size(DisplayWidth(display, screen), DisplayHeight(display, screen));
  XCloseDisplay(display);
  return size;
}

std::optional<cv::Size> Window::fitted() const {
  const auto screen = screen_size();
  if (!screen) return std::nullopt;
  // Keep the aspect: a square view stays square on a wide or a tall screen.
  const double fit = std::min({1.0, static_cast<double>(screen->width - kScreenMargin_px) / requested_.width,
                               static_cast<double>(screen->height - kScreenMargin_px) / requested_.height});
  const cv::Size size(std::max(kMinimumSide_px, static_cast<int>(requested_.width * fit)),
                      std::max(kMinimumSide_px, static_cast<int>(requested_.height * fit)));
  if (size != requested_)
    spdlog::info("tachi-viewer: window {}x{} to fit the {}x{} screen", size.width, size.height, screen->width, screen->height);
  return size;
}

Window::Window(std::string name, cv::Size requested) : name_(std::move(name)), requested_(requested) {
  const auto fits = fitted();
  screen_known_ = fits.has_value();
  size_ = fits.value_or(requested_);
  // GUI_NORMAL: no toolbar (its zoom would fight ours) and a window that can shrink; FREERATIO: the
  // image follows the window, and every frame is rendered at the window's size.
  cv::namedWindow(name_, cv::WINDOW_NORMAL | cv::WINDOW_GUI_NORMAL | cv::WINDOW_FREERATIO);
  cv::resizeWindow(name_, size_.width, size_.height);
  cv::moveWindow(name_, 0, 0);
  cv::setMouseCallback(name_, &Window::on_mouse, this);
}

Window::~Window() {
  if (display_ != nullptr) XCloseDisplay(static_cast<Display*>(display_));
  try {
    cv::destroyWindow(name_);
    cv::waitKey(1);
  } catch (const cv::Exception&) {
    // the user closed it already
  }
}

cv::Size Window::image_size() const {
  try {
    const cv::Rect area = cv::getWindowImageRect(name_);
    if (area.width >= kMinimumSide_px && area.height >= kMinimumSide_px) return area.size();
  } catch (const cv::Exception&) {
  }
  return size_;
}

void Window::show(const cv::Mat& image) { cv::imshow(name_, image); }

int Window::poll(int wait_ms) {
  const int key = cv::waitKeyEx(std::max(wait_ms, 1));
  if (hide_pointer_ && !pointer_hidden_) apply_hidden_pointer();
  if (!fit_settled_) settle_fit();
  return key;
}

void Window::settle_fit() {
  // The size asked for at creation does not always hold: the screen may not answer yet when the window is
  // made (an X server still starting), or a window manager may map the window at the requested size. A
  // test's server that was not ready left a 1000 px window on a 700 px screen (ctest, 2026-12-05). Until
  // the window is seen at the fitted size (then it is the user's to resize), the screen is asked again
  // and a larger window resized, now and then for a few seconds of polls.
  if (fit_checks_ > 300 || fit_checks_++ % 10 != 0) return;
  if (!screen_known_) {  // the screen did not answer at creation: asked again
    const auto fits = fitted();
    if (!fits) return;
    screen_known_ = true;
    size_ = *fits;
  }
  cv::Rect area;
  try {
    area = cv::getWindowImageRect(name_);
  } catch (const cv::Exception&) {
    return;
  }
  if (area.width < kMinimumSide_px || area.height < kMinimumSide_px) return;  // not mapped yet
  if (area.width > size_.width + 2 || area.height > size_.height + 2) {
    spdlog::debug("tachi-viewer: window {}x{}, larger than the {}x{} that fits; resized again", area.width, area.height,
                  size_.width, size_.height);
    cv::resizeWindow(name_, size_.width, size_.height);
    return;
  }
  fit_settled_ = true;
}

void Window::apply_hidden_pointer() {
  // The window appears some event loops after it was created: look for it now and then, not forever.
  if (pointer_attempts_ > 300 || pointer_attempts_++ % 10 != 0) return;
  if (display_ == nullptr) display_ = XOpenDisplay(nullptr);
  auto* display = static_cast<Display*>(display_);
  if (display == nullptr) return;
  const ::Window window = find_window(display, DefaultRootWindow(display), name_);
  if (window == 0) return;
  // A cursor whose 1x1 shape and mask are empty: nothing is drawn.
  static const char kEmpty[1] = {0};
  const Pixmap blank = XCreateBitmapFromData(display, window, kEmpty, 1, 1);
  XColor black{};
  const Cursor cursor = XCreatePixmapCursor(display, blank, blank, &black, &black, 0, 0);
  XDefineCursor(display, window, cursor);
  XFreePixmap(display, blank);
  XFlush(display);
  pointer_hidden_ = true;
}

bool Window::open() const {
  try {
    return cv::getWindowProperty(name_, cv::WND_PROP_VISIBLE) > 0.0;
  } catch (const cv::Exception&) {
    return false;
  }
}

std::vector<MouseEvent> Window::take_mouse_events() {
  std::vector<MouseEvent> events;
  events.swap(events_);
  return events;
}

void Window::on_mouse(int event, int x, int y, int flags, void* self) {
  auto& window = *static_cast<Window*>(self);
  MouseEvent e;
  e.pixel = cv::Point2f(static_cast<float>(x), static_cast<float>(y));
  e.shift = (flags & cv::EVENT_FLAG_SHIFTKEY) != 0;
  switch (event) {
    case cv::EVENT_MOUSEMOVE: e.kind = MouseEvent::Move; break;
    case cv::EVENT_LBUTTONDOWN: e.kind = MouseEvent::LeftDown; break;
    case cv::EVENT_LBUTTONUP: e.kind = MouseEvent::LeftUp; break;
    case cv::EVENT_RBUTTONDOWN: e.kind = MouseEvent::RightDown; break;
    case cv::EVENT_RBUTTONUP: e.kind = MouseEvent::RightUp; break;
    case cv::EVENT_MOUSEWHEEL:
      e.kind = MouseEvent::Wheel;
      e.wheel = cv::getMouseWheelDelta(flags);
      break;
    default: return;
  }
  window.events_.push_back(e);
}

}  // namespace tachi::viewer

namespace tachi::viewer {
std::unique_ptr<ViewerWindow> open_window(const ViewerOptions& options) {
  if (options.headless) return nullptr;
  if (std::getenv("DISPLAY") == nullptr)
    throw std::runtime_error(options.mesh.empty()
                                 ? "no display (DISPLAY is not set); use --headless with --video, --snapshot or --frames-dir"
                                 : "no display (DISPLAY is not set); use --headless --snapshot");
  return std::make_unique<Window>("tachi", cv::Size(options.size, options.size));
}
}  // namespace tachi::viewer
