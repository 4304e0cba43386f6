// The sensor stages as classes (the process is a deployment choice; sensor/main.cpp and voice_main.cpp only
// parse flags): SensorNode, depth frames in (live Kinect v1 or a fakenect recording), one raw hand sample
// out per frame (DDS and/or CSV); VoiceNode, audio in (WAV/raw file, ALSA device, the Kinect's microphones),
// spotted commands out (stdout and DDS). Linked from tachi_sensor_node and tachi_voice_node, which add DDS.
#pragma once

#include "tachi/sensor/voice_commands.hpp"

#include <cstdint>
#include <memory>
#include <string>

namespace tachi::bus {
class Participant;
}

namespace tachi::sensor {

struct SensorNodeOptions {
  std::string recording;    ///< fakenect folder; empty: the live Kinect
  std::string rate = "1";   ///< recording pace: real (=1), max, or a factor of real time
  bool loop = false;
  std::string record;       ///< also write every depth frame here (fakenect format)
  std::string csv;          ///< frame,stamp_ns,x,y,z,u,v,tracked,confidence per depth frame
  std::string calibration;  ///< live Kinect calibration JSON
  unsigned sensor_id = 0;
  unsigned wait_readers = 0;     ///< before the first frame, wait up to 5 s for this many readers
  std::uint64_t max_frames = 0;  ///< 0: no limit
  std::string resume;            ///< recording progress file (a restarted sensor goes on after it)
  int device = 0;
};

class SensorNode {
 public:
  /// Opens the source (throws NoKinectError without a Kinect) and, when `dds` is given (it must outlive the
  /// node), the raw hand writer. A resumed playback runs the frames published before through the finder.
  SensorNode(const SensorNodeOptions& options, bus::Participant* dds);
  ~SensorNode();
  SensorNode(const SensorNode&) = delete;
  SensorNode& operator=(const SensorNode&) = delete;
  /// One depth frame; false at the end of the recording or after --max-frames.
  bool spin_once();
  /// Flushes the CSV and the recording, lets matched readers acknowledge (300 ms at most). The exit code.
  int finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct VoiceNodeOptions {
  std::string wav;         ///< a WAV file to process, then stop
  std::string raw;         ///< a headerless 16 kHz s16le mono file to process, then stop
  std::string device;      ///< an ALSA capture device (live)
  bool kinect_mic = false; ///< the Kinect's microphones (live)
  int kinect_index = 0;
  double wait_readers_s = 1.0;  ///< with a file: how long to wait for a subscriber before publishing
  unsigned source_id = 0;
};

class VoiceNode {
 public:
  /// Reads the file or opens the device (throws AudioDeviceNotFound); publishes on `dds` when given.
  VoiceNode(const VoiceNodeOptions& options, const VoiceConfig& config, bus::Participant* dds);
  ~VoiceNode();
  VoiceNode(const VoiceNode&) = delete;
  VoiceNode& operator=(const VoiceNode&) = delete;
  /// One audio block through the spotter; every command printed (time_s,command,phrase) and published.
  /// False at the end of a file or when the device fails.
  bool spin_once();
  /// The spotter's last words (a file), then reliable delivery of what was written (2 s at most).
  int finish();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tachi::sensor
