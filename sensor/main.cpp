// tachi-sensor: depth frames in (live Kinect v1 or a fakenect recording), one raw hand sample out
// per depth frame (DDS topic tachi/hand/raw, and/or a CSV).
#include <chrono>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <thread>

#include <spdlog/spdlog.h>

#include "src/bus_adapter.hpp"
#include "tachi/bus/bus.hpp"
#include "tachi/bus/heartbeat.hpp"
#include "tachi/bus/topics.hpp"
#include "tachi/common/app.hpp"
#include "tachi/common/latency.hpp"
#include "tachi/common/peer_wait.hpp"
#include "tachi/sensor/depth_source.hpp"
#include "tachi/sensor/hand_csv.hpp"
#include "tachi/sensor/hand_finder.hpp"
#include "tachi/sensor/kinect_source.hpp"
#include "tachi/sensor/playback_progress.hpp"

namespace {

struct Options {
  std::string recording;
  bool live = false;
  std::string rate = "1";
  bool loop = false;
  std::string record;
  std::string csv;
  std::string calibration;
  bool no_dds = false;
  tachi::common::BusOptions bus;
  unsigned sensor_id = 0;
  unsigned wait_readers = 0;
  std::uint64_t max_frames = 0;
  std::string resume;
  int device = 0;
  std::string log_level;
};

/// "max" -> 0 (as fast as possible), "real" -> 1, else a positive factor of real time.
double parse_rate(const std::string& text) {
  if (text == "max") return 0.0;
  if (text == "real") return 1.0;
  return std::stod(text);
}

std::unique_ptr<tachi::sensor::DepthSource> open_source(const Options& o, std::uint64_t resume_after) {
  using namespace tachi::sensor;
  if (!o.recording.empty()) {
    auto source = std::make_unique<RecordingSource>(o.recording, Playback{parse_rate(o.rate), o.loop, resume_after});
    if (!o.calibration.empty()) spdlog::warn("--calibration ignored: the recording's own calibration (or the default) applies");
    spdlog::info("playing {} ({} depth frames, rate {})", o.recording, source->depth_frame_count(), o.rate);
    return source;
  }
  if (o.loop || o.rate != "1") spdlog::warn("--rate and --loop apply to recordings; the live Kinect runs at its own 30 Hz");
  const DepthModel model = o.calibration.empty() ? DepthModel{} : load_calibration(o.calibration);
  return std::make_unique<KinectSource>(o.device, model, [] { return tachi::common::stop_requested(); });
}

}  // namespace

int main(int argc, char** argv) try {
  CLI::App app{"tachi-sensor: Kinect v1 depth (live or fakenect recording) -> palm centre per depth frame"};
  app.name("tachi-sensor");
  Options o;
  auto* rec = app.add_option("--recording", o.recording, "Play a fakenect recording folder instead of the live Kinect")
                  ->check(CLI::ExistingDirectory);
  app.add_flag("--live", o.live, "Use the live Kinect (the default without --recording)")->excludes(rec);
  app.add_option("--rate", o.rate, "Recording pace: real (=1), max (as fast as possible) or a factor of real time")
      ->check([](const std::string& s) -> std::string {
        if (s == "max" || s == "real") return {};
        try {
          std::size_t used = 0;
          const double r = std::stod(s, &used);
          if (used == s.size() && r > 0 && r <= 1000) return {};
        } catch (const std::exception&) {
        }
        return "must be real, max or a factor in (0, 1000]";
      })
      ->capture_default_str();
  app.add_flag("--loop", o.loop, "Replay the recording forever");
  app.add_option("--record", o.record, "Also write every depth frame to this new folder (fakenect format)");
  app.add_option("--csv", o.csv, "Write frame,stamp_ns,x,y,z,u,v,tracked,confidence per depth frame");
  app.add_option("--calibration", o.calibration, "Calibration JSON for the live Kinect (fx, fy, cx, cy, disparity_a, disparity_b)")
      ->check(CLI::ExistingFile);
  app.add_option("--device", o.device, "Kinect index (live)")->check(CLI::Range(0, 15))->capture_default_str();
  app.add_flag("--no-dds", o.no_dds, "Do not publish on DDS");
  tachi::common::add_bus_flags(app, o.bus);
  app.add_option("--sensor-id", o.sensor_id, "sensor_id of the published samples")->capture_default_str();
  app.add_option("--wait-readers", o.wait_readers, "Before the first frame, wait up to 5 s for this many DDS readers")
      ->check(CLI::Range(0u, 64u));
  app.add_option("--max-frames", o.max_frames, "Stop after this many depth frames (0 = no limit)");
  app.add_option("--resume", o.resume,
                 "Recording: keep the count of published frames in this file and, when it already holds one, "
                 "continue after that frame (a restarted sensor does not play the recording from the top; tachi run "
                 "passes it)")
      ->needs(rec);
  tachi::common::add_log_level_flag(app, o.log_level);
  if (const int rc = tachi::common::parse(app, argc, argv); rc >= 0) return rc;
  tachi::common::set_log_level(o.log_level);
  tachi::common::install_stop_handlers();

  // A resumed playback runs the frames already published through the hand finder again, unpaced and
  // unpublished, so the finder's tracking state is the killed sensor's when it goes on.
  std::optional<tachi::sensor::PlaybackProgress> progress;
  if (!o.resume.empty()) progress.emplace(o.resume);
  const std::uint64_t resume_after = progress ? progress->resumed_after() : 0;
  std::unique_ptr<tachi::sensor::DepthSource> source;
  try {
    source = open_source(o, resume_after);
  } catch (const tachi::sensor::NoKinectError& e) {
    std::cerr << "tachi-sensor: " << e.what() << '\n';
    return tachi::common::kExitNoDevice;
  }

  std::optional<tachi::sensor::FakenectWriter> recorder;
  if (!o.record.empty()) {
    recorder.emplace(o.record);
    tachi::sensor::save_calibration(std::filesystem::path(o.record) / tachi::sensor::kCalibrationFile, source->model());
  }
  std::ofstream csv;
  if (!o.csv.empty()) {
    csv.open(o.csv);
    if (!csv) throw std::runtime_error("cannot write " + o.csv);
    csv << tachi::sensor::kHandCsvHeader << '\n';
  }
  std::optional<tachi::bus::Participant> dds;
  std::optional<tachi::bus::Writer<tachi_msg_RawHandSample>> writer;
  std::optional<tachi::bus::Heartbeat> heartbeat;
  if (!o.no_dds) {
    dds.emplace(o.bus.domain, o.bus.dds_config, tachi::bus::Security{o.bus.secure_dir, o.bus.identity});
    writer.emplace(*dds, tachi::bus::topics::raw_hand);
    heartbeat.emplace(*dds, "tachi-sensor");
    if (o.wait_readers > 0 && !writer->wait_for_readers(o.wait_readers, std::chrono::seconds(5)))
      spdlog::warn("only {} of {} readers after 5 s; publishing anyway", writer->matched_readers(), o.wait_readers);
  }

  tachi::sensor::use_one_opencv_thread();
  tachi::sensor::HandFinder finder(source->model());
  std::uint64_t frames = 0, tracked = 0;
  tachi::sensor::DepthFrame buffer;  // reused: no 614 KB allocation (and its page faults) per frame
  tachi::common::LatencyWindow latency;
  tachi::common::PeerWait waiting_for_filter("tachi-filter", o.bus.domain);
  const auto started = std::chrono::steady_clock::now();
  while (!tachi::common::stop_requested() && (o.max_frames == 0 || frames < o.max_frames)) {
    if (!source->next_into(buffer)) break;
    const tachi::sensor::DepthFrame* frame = &buffer;
    // End-to-end latency starts when the frame reaches this process (the recording's pacing is before it).
    const std::int64_t acquired_ns = tachi::common::wall_clock_ns();
    const auto hand = finder.find(*frame);
    if (frames < resume_after) {
      ++frames;
      tracked += hand.tracked ? 1 : 0;
      if (frames == resume_after) spdlog::info("resumed {} after frame {} (from {})", o.recording, frames, o.resume);
      continue;
    }
    if (recorder) {
      recorder->write_depth(*frame);
      if (frame->accel) recorder->write_accel(frame->stamp_ns, frame->device_timestamp, *frame->accel);
    }
    if (csv.is_open()) tachi::sensor::write_hand_row(csv, frame->frame, frame->stamp_ns, hand);
    if (writer) writer->write(tachi::sensor::to_msg(hand, o.sensor_id, frame->frame, frame->stamp_ns, acquired_ns));
    ++frames;
    tracked += hand.tracked ? 1 : 0;
    if (progress) progress->record(frames);  // after publishing: a kill in between resends a frame, never skips one
    latency.add_since(acquired_ns, tachi::common::wall_clock_ns());
    if (heartbeat) {
      const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
      heartbeat->set_metric("frames", static_cast<double>(frames));
      heartbeat->set_metric("tracked_frames", static_cast<double>(tracked));
      heartbeat->set_metric("fps", elapsed_s > 0 ? static_cast<double>(frames) / elapsed_s : 0.0);
      heartbeat->set_metric("latency_p50_ms", latency.percentile(50));
      heartbeat->set_metric("latency_p99_ms", latency.percentile(99));
      heartbeat->update(tachi_msg_NODE_RUNNING, frames, frames, hand.tracked ? "hand tracked" : "no hand");
    }
    if (writer) waiting_for_filter.warn_if_waiting(writer->matched_readers() > 0);
  }
  if (csv.is_open() && !csv.flush()) throw std::runtime_error("cannot write " + o.csv);
  if (recorder) recorder->flush();
  // Samples still in flight: the matched readers acknowledge them before the writer goes (300 ms at most).
  if (writer && writer->matched_readers() > 0) writer->wait_for_acks(std::chrono::milliseconds(300));
  spdlog::info("{} depth frames, hand tracked in {}", frames, tracked);
  return tachi::common::kExitOk;
} catch (const std::exception& e) {
  std::cerr << "tachi-sensor: " << e.what() << '\n';
  return tachi::common::kExitFailure;
}
