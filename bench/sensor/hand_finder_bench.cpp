// tachi-sensor-bench: ms per 640x480 frame for hand extraction (one core) and accuracy on every
// bundled scenario, for tachi's HandFinder and for a nearest-blob baseline (full-frame depth band
// around the nearest reading + full-frame distance transform), both run here on the same frames.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <time.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "paths.hpp"
#include "tachi/common/app.hpp"
#include "tachi/sensor/depth_source.hpp"
#include "tachi/sensor/hand_csv.hpp"
#include "tachi/sensor/hand_finder.hpp"

namespace {

using namespace tachi::sensor;

/// The obvious approach: the nearest blob is the hand.
HandObservation nearest_blob(const std::vector<std::uint16_t>& raw, const DepthModel& model) {
  HandObservation out;
  const std::uint16_t nearest = *std::min_element(raw.begin(), raw.end());
  if (nearest >= kNoReading) return out;
  const auto far = static_cast<std::uint16_t>(model.raw_at(model.metres(nearest) + 0.07));
  const cv::Mat depth(kDepthHeight, kDepthWidth, CV_16U, const_cast<std::uint16_t*>(raw.data()));
  cv::Mat mask, dist;
  cv::inRange(depth, cv::Scalar(nearest), cv::Scalar(far), mask);
  cv::distanceTransform(mask, dist, cv::DIST_L2, cv::DIST_MASK_PRECISE);  // the faster mode on a full frame
  double r = 0;
  cv::Point at;
  cv::minMaxLoc(dist, nullptr, &r, nullptr, &at);
  if (r < 2) return out;
  std::vector<std::uint16_t> palm;
  for (int y = std::max(0, at.y - static_cast<int>(r)); y <= std::min(kDepthHeight - 1, at.y + static_cast<int>(r)); ++y)
    for (int x = std::max(0, at.x - static_cast<int>(r)); x <= std::min(kDepthWidth - 1, at.x + static_cast<int>(r)); ++x)
      if ((x - at.x) * (x - at.x) + (y - at.y) * (y - at.y) <= r * r && mask.at<std::uint8_t>(y, x)) palm.push_back(raw[static_cast<std::size_t>(y) * kDepthWidth + x]);
  std::nth_element(palm.begin(), palm.begin() + static_cast<std::ptrdiff_t>(palm.size() / 2), palm.end());
  const float z = model.metres(palm[palm.size() / 2]);
  out.tracked = true;
  out.position_m = model.back_project(at.x, at.y, z).cast<float>();
  return out;
}

/// CPU time of this thread: on a shared, loaded machine wall time also counts other processes.
double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) / 1e6;
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

template <class Find>
std::pair<std::vector<double>, Evaluation> run(const std::vector<DepthFrame>& frames, const std::vector<TruthRow>& truth,
                                               int repeat, Find make_and_find) {
  std::vector<double> ms;
  std::vector<HandRow> rows;
  for (int pass = 0; pass < repeat; ++pass) {
    auto find = make_and_find();
    rows.clear();
    for (const auto& f : frames) {
      const double t0 = thread_cpu_ms();
      const HandObservation h = find(f);
      ms.push_back(thread_cpu_ms() - t0);
      HandRow r;
      r.frame = f.frame;
      r.tracked = h.tracked;
      r.position = h.position_m.cast<double>();
      rows.push_back(r);
    }
  }
  return {ms, evaluate(rows, truth)};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"tachi-sensor-bench: hand extraction speed and accuracy on the bundled recordings, against a "
               "nearest-blob baseline (docs/benchmarks.md)"};
  app.name("tachi-sensor-bench");
  std::string recordings = tachi::test::recordings_dir();
  int repeat = 5;
  std::string per_frame_word;
  app.add_option("recordings", recordings, "Folder of rendered recordings: every subfolder with a ground_truth.csv is run, in name order")
      ->check(CLI::ExistingDirectory)
      ->capture_default_str();
  app.add_option("passes", repeat, "Passes per scenario")->check(CLI::Range(1, 1000))->capture_default_str();
  app.add_option("per-frame", per_frame_word, "\"per-frame\": also print the first pass's ms per frame to stderr")
      ->check(CLI::IsMember({"per-frame"}));
  if (const int rc = tachi::common::parse(app, argc, argv); rc >= 0) return rc;
  const std::filesystem::path dir = recordings;
  const bool per_frame = !per_frame_word.empty();
  std::printf("recordings %s, %d passes per scenario, one thread, thread CPU time per frame\n\n", dir.c_str(), repeat);
  std::printf("%-13s %6s | %9s %9s %7s %5s | %9s %9s %7s %5s | %7s\n", "scenario", "frames", "tachi ms", "RMS mm",
              "tracked", "phant", "blob ms", "RMS mm", "tracked", "phant", "speedup");
  std::vector<double> all_ours, all_base;
  // Every rendered scenario (a folder with a ground truth), in name order.
  std::error_code error;
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir, error))
    if (std::filesystem::exists(entry.path() / "ground_truth.csv")) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  if (error || names.empty()) {
    // Nothing to time (a tree whose recordings are another tree's, TACHI_RECORDINGS_FROM): no figures to print.
    std::fprintf(stderr, "tachi-sensor-bench: %s: no recordings in it (folders with a ground_truth.csv)%s%s\n",
                 dir.c_str(), error ? ": " : "", error ? error.message().c_str() : "");
    return 1;
  }
  for (const auto& name : names) {
    try {
      RecordingSource source(dir / name, Playback{0.0, false});
      const DepthModel model = source.model();
      std::vector<DepthFrame> frames;
      while (auto f = source.next()) frames.push_back(std::move(*f));
      const auto truth = read_truth_csv(dir / name / "ground_truth.csv");
      const auto [ours_ms, ours] = run(frames, truth, repeat, [&] {
        return [finder = std::make_shared<HandFinder>(model)](const DepthFrame& f) { return finder->find(f); };
      });
      if (per_frame) {
        for (std::size_t i = 0; i < ours_ms.size() && i < frames.size(); ++i) std::fprintf(stderr, "%s %zu %.3f\n", name.c_str(), i, ours_ms[i]);
      }
      const auto [base_ms, base] = run(frames, truth, repeat, [&] {
        return [&model](const DepthFrame& f) { return nearest_blob(f.raw, model); };
      });
      all_ours.insert(all_ours.end(), ours_ms.begin(), ours_ms.end());
      all_base.insert(all_base.end(), base_ms.begin(), base_ms.end());
      std::printf("%-13s %6zu | %9.3f %9.2f %7.4f %5zu | %9.3f %9.1f %7.4f %5zu | %6.1fx\n", name.c_str(), frames.size(),
                  median(ours_ms), ours.rms_m * 1000, ours.tracked_ratio, ours.phantoms, median(base_ms), base.rms_m * 1000,
                  base.tracked_ratio, base.phantoms, median(base_ms) / median(ours_ms));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "tachi-sensor-bench: %s: %s\n", name.c_str(), e.what());
      return 1;
    }
  }
  std::vector<double> sorted = all_ours;
  std::sort(sorted.begin(), sorted.end());
  std::printf("\nall frames: tachi median %.3f ms (p90 %.3f, max %.3f); nearest blob median %.3f ms; ratio %.1fx\n",
              median(all_ours), sorted[sorted.size() * 9 / 10], sorted.back(), median(all_base),
              median(all_base) / median(all_ours));
  return 0;
}
