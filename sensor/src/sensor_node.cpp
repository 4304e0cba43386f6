#include "bus_adapter.hpp"
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
#include "tachi/sensor/node.hpp"
#include "tachi/sensor/playback_progress.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <optional>

namespace tachi::sensor {
namespace {

/// "max" -> 0 (as fast as possible), "real" -> 1, else a positive factor of real time.
double parse_rate(const std::string& text) {
  if (text == "max") return 0.0;
  if (text == "real") return 1.0;
  return std::stod(text);
}

std::unique_ptr<DepthSource> open_source(const SensorNodeOptions& o, std::uint64_t resume_after) {
  if (!o.recording.empty()) {
    auto source = std::make_unique<RecordingSource>(o.recording, Playback{parse_rate(o.rate), o.loop, resume_after});
    if (!o.calibration.empty()) spdlog::warn("--calibration ignored: the recording's own calibration (or the default) applies");
    spdlog::info("playing {} ({} depth frames, rate {})", o.recording, source->depth_frame_count(), o.rate);
    return source;
  }
  if (o.loop || o.rate != "1") spdlog::warn("--rate and --loop apply to recordings; the live Kinect runs at its own 30 Hz");
  const DepthModel model = o.calibration.empty() ? DepthModel{} : load_calibration(o.calibration);
  return std::make_unique<KinectSource>(o.device, model, [] { return common::stop_requested(); });
}

// A resumed playback runs the frames already published through the hand finder again, unpaced and
// unpublished, so the finder's tracking state is the killed sensor's when it goes on.
std::optional<PlaybackProgress> open_progress(const std::string& path) {
  if (path.empty()) return std::nullopt;
  return std::optional<PlaybackProgress>{std::in_place, path};
}

}  // namespace

struct SensorNode::Impl {
  Impl(const SensorNodeOptions& options, bus::Participant* dds)
      : o(options), progress(open_progress(o.resume)), resume_after(progress ? progress->resumed_after() : 0),
        source(open_source(o, resume_after)), finder(source->model()), waiting_for_filter("tachi-filter", dds ? dds->domain() : 0),
        started(std::chrono::steady_clock::now()) {
    if (!o.record.empty()) {
      recorder.emplace(o.record);
      save_calibration(std::filesystem::path(o.record) / kCalibrationFile, source->model());
    }
    if (!o.csv.empty()) {
      csv.open(o.csv);
      if (!csv) throw std::runtime_error("cannot write " + o.csv);
      csv << kHandCsvHeader << '\n';
    }
    if (dds != nullptr) {
      writer.emplace(*dds, bus::topics::raw_hand);
      heartbeat.emplace(*dds, "tachi-sensor");
      if (o.wait_readers > 0 && !writer->wait_for_readers(o.wait_readers, std::chrono::seconds(5)))
        spdlog::warn("only {} of {} readers after 5 s; publishing anyway", writer->matched_readers(), o.wait_readers);
    }
    use_one_opencv_thread();
  }

  bool spin_once() {
    if (o.max_frames != 0 && frames >= o.max_frames) return false;
    if (!source->next_into(buffer)) return false;
    const DepthFrame* frame = &buffer;
    // End-to-end latency starts when the frame reaches this process (the recording's pacing is before it).
    const std::int64_t acquired_ns = common::wall_clock_ns();
    const auto hand = finder.find(*frame);
    if (frames < resume_after) {
      ++frames;
      tracked += hand.tracked ? 1 : 0;
      if (frames == resume_after) spdlog::info("resumed {} after frame {} (from {})", o.recording, frames, o.resume);
      return true;
    }
    if (recorder) {
      recorder->write_depth(*frame);
      if (frame->accel) recorder->write_accel(frame->stamp_ns, frame->device_timestamp, *frame->accel);
    }
    if (csv.is_open()) write_hand_row(csv, frame->frame, frame->stamp_ns, hand);
    if (writer) writer->write(to_msg(hand, o.sensor_id, frame->frame, frame->stamp_ns, acquired_ns));
    ++frames;
    tracked += hand.tracked ? 1 : 0;
    if (progress) progress->record(frames);  // after publishing: a kill in between resends a frame, never skips one
    latency.add_since(acquired_ns, common::wall_clock_ns());
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
    return true;
  }

  int finish() {
    if (csv.is_open() && !csv.flush()) throw std::runtime_error("cannot write " + o.csv);
    if (recorder) recorder->flush();
    // Samples still in flight: the matched readers acknowledge them before the writer goes (300 ms at most).
    if (writer && writer->matched_readers() > 0) writer->wait_for_acks(std::chrono::milliseconds(300));
    spdlog::info("{} depth frames, hand tracked in {}", frames, tracked);
    return common::kExitOk;
  }

  const SensorNodeOptions o;
  std::optional<PlaybackProgress> progress;
  const std::uint64_t resume_after;
  std::unique_ptr<DepthSource> source;
  std::optional<FakenectWriter> recorder;
  std::ofstream csv;
  std::optional<bus::Writer<tachi_msg_RawHandSample>> writer;
  std::optional<bus::Heartbeat> heartbeat;
  HandFinder finder;
  std::uint64_t frames = 0, tracked = 0;
  DepthFrame buffer;  // reused: no 614 KB allocation (and its page faults) per frame
  common::LatencyWindow latency;
  common::PeerWait waiting_for_filter;
  const std::chrono::steady_clock::time_point started;
};

SensorNode::SensorNode(const SensorNodeOptions& options, bus::Participant* dds)
    : impl_(std::make_unique<Impl>(options, dds)) {}
SensorNode::~SensorNode() = default;
bool SensorNode::spin_once() { return impl_->spin_once(); }
int SensorNode::finish() { return impl_->finish(); }

}  // namespace tachi::sensor
