// Whole-process cost of tachi-sensor over each bundled recording (`--rate max --no-dds`: reading the
// fakenect files, decoding, hand extraction, the CSV), against hand extraction alone run in this
// process on the same frames. Whole process: the child's CPU time (user + system, from wait4's
// rusage) per frame, less a start-up run of the same command with `--max-frames 1`. Extraction:
// HandFinder::find's thread CPU time per frame. Medians over the passes, and the fastest pass (the
// least disturbed by other processes on a shared machine). Results: docs/benchmarks.md.
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "paths.hpp"
#include "tachi/sensor/depth_source.hpp"
#include "tachi/sensor/hand_finder.hpp"

extern char** environ;

namespace {

using namespace tachi::sensor;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

/// CPU seconds (user + system) of one run of `argv`; negative if it could not run or failed.
double child_cpu_s(std::vector<std::string> args) {
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0) return -1;
  int status = 0;
  rusage usage{};
  if (wait4(pid, &status, 0, &usage) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0) return -1;
  const auto s = [](const timeval& t) { return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_usec) * 1e-6; };
  return s(usage.ru_utime) + s(usage.ru_stime);
}

double thread_cpu_ms() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help") {
    std::printf("usage: tachi-sensor-process-bench TACHI_SENSOR_EXE [RECORDINGS_DIR] [PASSES]\n");
    return argc < 2 ? 2 : 0;
  }
  const std::string exe = argv[1];
  const std::filesystem::path dir = argc > 2 ? argv[2] : tachi::test::recordings_dir();
  const int passes = argc > 3 ? std::max(1, std::atoi(argv[3])) : 5;
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir))
    if (std::filesystem::exists(entry.path() / "ground_truth.csv")) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());

  use_one_opencv_thread();
  std::printf("%s over %s, %d passes, CPU ms per frame (medians)\n\n", exe.c_str(), dir.c_str(), passes);
  std::printf("%-17s %6s | %13s %11s | %7s\n", "scenario", "frames", "whole process", "extraction", "ratio");
  std::vector<double> all_process, all_extract;
  double frames_total = 0, min_process = 0, min_extract = 0;  // sums of per-scenario minima (x frames)
  for (const auto& name : names) {
    const std::string rec = (dir / name).string();
    RecordingSource source(rec, Playback{0.0, false});
    std::vector<DepthFrame> frames;
    while (auto f = source.next()) frames.push_back(std::move(*f));
    const auto n = static_cast<double>(frames.size());
    std::vector<double> process_ms, extract_ms;
    for (int pass = 0; pass < passes; ++pass) {
      const double whole = child_cpu_s({exe, "--recording", rec, "--rate", "max", "--no-dds", "--csv", "/dev/null", "--log-level", "warn"});
      const double start = child_cpu_s({exe, "--recording", rec, "--rate", "max", "--no-dds", "--csv", "/dev/null", "--log-level",
                                        "warn", "--max-frames", "1"});
      if (whole < 0 || start < 0) {
        std::fprintf(stderr, "tachi-sensor-process-bench: %s failed on %s\n", exe.c_str(), rec.c_str());
        return 1;
      }
      process_ms.push_back(std::max(0.0, whole - start) * 1e3 / (n - 1));
      HandFinder finder(source.model());
      const double t0 = thread_cpu_ms();
      for (const auto& f : frames) finder.find(f);
      extract_ms.push_back((thread_cpu_ms() - t0) / n);
    }
    const double p = median(process_ms), e = median(extract_ms);
    min_process += *std::min_element(process_ms.begin(), process_ms.end()) * n;
    min_extract += *std::min_element(extract_ms.begin(), extract_ms.end()) * n;
    all_process.push_back(p * n);
    all_extract.push_back(e * n);
    frames_total += n;
    std::printf("%-17s %6zu | %13.3f %11.3f | %6.2fx\n", name.c_str(), frames.size(), p, e, p / e);
  }
  double p = 0, e = 0;
  for (std::size_t i = 0; i < all_process.size(); ++i) {
    p += all_process[i];
    e += all_extract[i];
  }
  std::printf("\nall %0.f frames: whole process %.3f ms per frame, extraction %.3f ms, ratio %.2fx\n", frames_total,
              p / frames_total, e / frames_total, p / e);
  // On a shared machine other processes only ever add time: the fastest pass is the least disturbed.
  std::printf("all %0.f frames, fastest pass of each: whole process %.3f ms per frame, extraction %.3f ms, ratio %.2fx\n",
              frames_total, min_process / frames_total, min_extract / frames_total, min_process / min_extract);
  return 0;
}
