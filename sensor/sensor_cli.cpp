#include "cli.hpp"

namespace tachi::sensor {

int parse_sensor_flags(int argc, char** argv, SensorFlags& flags) {
  CLI::App app{"tachi-sensor: Kinect v1 depth (live or fakenect recording) -> palm centre per depth frame"};
  app.name("tachi-sensor");
  SensorNodeOptions& o = flags.options;
  bool live = false;
  std::string log_level;
  auto* rec = app.add_option("--recording", o.recording, "Play a fakenect recording folder instead of the live Kinect")
                  ->check(CLI::ExistingDirectory);
  app.add_flag("--live", live, "Use the live Kinect (the default without --recording)")->excludes(rec);
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
  app.add_flag("--no-dds", flags.no_dds, "Do not publish on DDS");
  common::add_bus_flags(app, flags.bus);
  app.add_option("--sensor-id", o.sensor_id, "sensor_id of the published samples")->capture_default_str();
  app.add_option("--wait-readers", o.wait_readers, "Before the first frame, wait up to 5 s for this many DDS readers")
      ->check(CLI::Range(0u, 64u));
  app.add_option("--max-frames", o.max_frames, "Stop after this many depth frames (0 = no limit)");
  app.add_option("--resume", o.resume,
                 "Recording: keep the count of published frames in this file and, when it already holds one, "
                 "continue after that frame (a restarted sensor does not play the recording from the top; tachi run "
                 "passes it)")
      ->needs(rec);
  common::add_log_level_flag(app, log_level);
  if (const int rc = common::parse(app, argc, argv); rc >= 0) return rc;
  common::set_log_level(log_level);
  return -1;
}

}  // namespace tachi::sensor
