// render_bench: how fast the viewer draws an N x N cloth (targets: 128^2 >= 30 fps, 256^2 >= 10 fps
// on one core). Draws a hanging, gently folded cloth with the HUD into an 800 x 800 image, the
// window's default size, from the front and from an orbited camera; prints the median frame time and
// the ratio to a 32 x 32 cloth drawn in the same process (the baseline), so a noisy machine still
// gives comparable figures. Usage: render_bench [--frames N] [--size PX]
#include "../bench_args.hpp"
#include "tachi/viewer/render.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

using tachi::viewer::Mesh;
using tachi::viewer::Scene;
using tachi::viewer::View;

namespace {
Mesh folded_cloth(int n) {
  Mesh mesh;
  for (int v = 0; v < n; ++v)
    for (int u = 0; u < n; ++u) {
      const float x = -0.5f + static_cast<float>(u) / static_cast<float>(n - 1);
      const float y = 0.5f - static_cast<float>(v) / static_cast<float>(n - 1);
      mesh.positions.emplace_back(x, y, 0.05f * std::sin(12.0f * x) * (0.5f - y));
    }
  for (int v = 0; v + 1 < n; ++v)
    for (int u = 0; u + 1 < n; ++u) {
      const auto i = static_cast<std::uint32_t>(v * n + u);
      const auto w = static_cast<std::uint32_t>(n);
      mesh.triangles.push_back({i, i + 1, i + w});
      mesh.triangles.push_back({i + 1, i + w + 1, i + w});
    }
  mesh.pinned.assign(mesh.positions.size(), 0);
  return mesh;
}

double median_ms(const Scene& scene, const View& view, int frames) {
  std::vector<double> ms;
  for (int i = 0; i < frames + 3; ++i) {
    const auto start = std::chrono::steady_clock::now();
    const cv::Mat image = tachi::viewer::render(scene, view);
    const auto stop = std::chrono::steady_clock::now();
    if (i >= 3 && !image.empty()) ms.push_back(std::chrono::duration<double, std::milli>(stop - start).count());
  }
  std::nth_element(ms.begin(), ms.begin() + static_cast<std::ptrdiff_t>(ms.size() / 2), ms.end());
  return ms[ms.size() / 2];
}
}  // namespace

int main(int argc, char** argv) {
  const char* usage = "usage: render_bench [--frames N=40] [--size PIXELS=800]   (N 1..100000, PIXELS 64..4096)\n";
  tachi::bench::exit_on_help(argc, argv, usage);
  int frames = 40;
  int size = 800;
  for (int i = 1; i < argc; i += 2) {
    if (i + 1 < argc && std::strcmp(argv[i], "--frames") == 0) {
      frames = tachi::bench::int_argument(argv[i + 1], "render_bench --frames", 1, 100000, usage);
    } else if (i + 1 < argc && std::strcmp(argv[i], "--size") == 0) {
      size = tachi::bench::int_argument(argv[i + 1], "render_bench --size", 64, 4096, usage);
    } else {
      std::fprintf(stderr, "render_bench: unknown argument '%s'\n%s", argv[i], usage);
      return 2;
    }
  }
  View front;
  front.width = front.height = size;
  View orbited = front;
  orbited.orbit(0.5f, 0.3f);
  std::printf("image %dx%d, %d frames per figure, median frame time\n", size, size, frames);
  std::printf("%-8s %-8s %10s %8s %14s\n", "cloth", "view", "ms/frame", "fps", "x 32^2 baseline");
  for (const View* view : {&front, &orbited}) {
    const char* name = view == &front ? "front" : "orbited";
    Scene scene;
    scene.hud.emplace();
    scene.mesh = folded_cloth(32);
    const double baseline = median_ms(scene, *view, frames);
    for (const int n : {32, 128, 256}) {
      scene.mesh = folded_cloth(n);
      const double ms = n == 32 ? baseline : median_ms(scene, *view, frames);
      std::printf("%3dx%-4d %-8s %10.2f %8.1f %14.2f\n", n, n, name, ms, 1000.0 / ms, ms / baseline);
    }
  }
  return 0;
}
