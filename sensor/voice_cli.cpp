#include "cli.hpp"

#include <iostream>

namespace tachi::sensor {

int parse_voice_flags(int argc, char** argv, VoiceFlags& flags) {
  CLI::App app{"tachi-voice: spots the spoken start/stop cutting commands and publishes them"};
  app.name("tachi-voice");
  VoiceNodeOptions& o = flags.options;
  std::string config_file, start_phrase, stop_phrase, grab_phrase, release_phrase, log_level;
  auto* wav = app.add_option("--wav", o.wav, "Process a WAV file (16-bit PCM, any rate/channels) and exit")
                  ->check(CLI::ExistingFile);
  auto* raw = app.add_option("--raw", o.raw, "Process a headerless 16 kHz s16le mono file and exit")->check(CLI::ExistingFile);
  auto* device = app.add_option("--device", o.device, "Listen to an ALSA capture device (e.g. default, hw:1,0)");
  auto* kinect = app.add_flag("--kinect-mic", o.kinect_mic, "Listen to the Kinect v1's microphone array");
  app.add_option("--kinect-index", o.kinect_index, "Which Kinect, with --kinect-mic")->check(CLI::Range(0, 15));
  wav->excludes(raw)->excludes(device)->excludes(kinect);
  raw->excludes(device)->excludes(kinect);
  device->excludes(kinect);
  app.add_option("--config", config_file, "Voice config JSON (see config/voice.json)")->check(CLI::ExistingFile);
  app.add_option("--start-phrase", start_phrase, "Phrase that starts cutting (default \"begin cutting\"; \"start cutting\" was the default before: British voices drop its R and are heard as \"stop\")");
  app.add_option("--stop-phrase", stop_phrase, "Phrase that stops cutting (default \"stop cutting\")");
  app.add_option("--grab-phrase", grab_phrase, "Phrase that makes the hand grab the cloth (none by default; e.g. \"grab cloth\")");
  app.add_option("--release-phrase", release_phrase, "Phrase that lets the grabbed cloth go (none by default; e.g. \"release cloth\")");
  app.add_flag("--no-dds", flags.no_dds, "Do not publish on the bus; only print");
  app.add_option("--wait-readers", o.wait_readers_s, "With a file: seconds to wait for a subscriber before publishing")
      ->check(CLI::Range(0.0, 60.0))
      ->capture_default_str();
  app.add_option("--source-id", o.source_id, "Key of the published commands")->capture_default_str();
  common::add_log_level_flag(app, log_level);
  common::add_bus_flags(app, flags.bus);
  if (const int rc = common::parse(app, argc, argv); rc >= 0) return rc;
  // Logs go to stderr: stdout carries the command lines and must stay parseable.
  common::set_log_level(log_level);

  VoiceConfig& config = flags.config;
  try {
    if (!config_file.empty()) config = load_voice_config(config_file);
    if (!start_phrase.empty()) set_phrase(config, VoiceCommand::Start, start_phrase);
    if (!stop_phrase.empty()) set_phrase(config, VoiceCommand::Stop, stop_phrase);
    if (!grab_phrase.empty()) set_phrase(config, VoiceCommand::Grab, grab_phrase);
    if (!release_phrase.empty()) set_phrase(config, VoiceCommand::Release, release_phrase);
    if (const auto why = validate(config)) throw std::invalid_argument(*why);
  } catch (const std::invalid_argument& e) {
    std::cerr << "tachi-voice: " << e.what() << '\n';
    return common::kExitUsage;
  }
  if (o.wav.empty() && o.raw.empty() && device->count() == 0 && !o.kinect_mic) {
    std::cerr << "tachi-voice: give an input: --wav FILE, --raw FILE, --device NAME or --kinect-mic\n";
    return common::kExitUsage;
  }
  return -1;
}

}  // namespace tachi::sensor
