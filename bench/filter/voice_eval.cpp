// Voice command evaluation: detection rate and false alarms of the keyword spotter.
//  1. Real speech (pocketsphinx-testdata): goforward.raw ("go forward ten meters") with "go forward", and the
//     cards recordings with the two-word phrases "of clubs" / "of spades" / "of hearts"; LibriVox reading
//     (ordinary speech) with the default phrases for false alarms.
//  2. Synthesised commands: flite voices saying "start cutting" / "stop cutting" at three speaking rates,
//     in sequences of 6 alternating commands with random pauses (0.3-1.5 s), gains (0.5-1) and white noise (clean, 30, 20, 10 dB SNR), half of them
//     interleaved with LibriVox reading. No recording of a person saying the default phrases exists here.
// Prints counts per group; docs/benchmarks.md ("Filter and voice") records a run.
#include "tachi/sensor/voice_spotter.hpp"
#include "tachi/common/app.hpp"
#include "voice_fixture.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <optional>
#include <random>

namespace {

using namespace tachi::sensor;
namespace fixture = tachi::sensor::testing;

struct Tally {
  int commands = 0;
  int detected = 0;       // right phrase, during or just after the utterance
  int wrong_command = 0;  // the other phrase at that time
  int false_alarms = 0;   // detections matching no utterance
  double audio_s = 0;
};

/// Matches detections to placed utterances: a detection counts for an utterance when it is reported
/// between the utterance's start and 0.6 s after its end.
void score(const std::vector<fixture::Placed>& placed, const std::vector<VoiceDetection>& found, Tally& t) {
  std::vector<bool> used(found.size(), false);
  for (const auto& p : placed) {
    ++t.commands;
    bool hit = false, wrong = false;
    for (std::size_t i = 0; i < found.size(); ++i) {
      if (used[i] || found[i].time_s < p.begin_s || found[i].time_s > p.end_s + 0.6) continue;
      used[i] = true;
      (found[i].phrase == p.phrase ? hit : wrong) = true;
    }
    t.detected += hit ? 1 : 0;
    t.wrong_command += (!hit && wrong) ? 1 : 0;
  }
  for (bool u : used) t.false_alarms += u ? 0 : 1;
}

void print(const char* group, const Tally& t) {
  std::printf("%-58s %5d %8d %7.1f%% %6d %7d %8.1f\n", group, t.commands, t.detected,
              t.commands ? 100.0 * t.detected / t.commands : 0.0, t.wrong_command, t.false_alarms, t.audio_s);
}

double rms(const std::vector<std::int16_t>& s) {
  double sum = 0;
  for (auto v : s) sum += static_cast<double>(v) * v;
  return std::sqrt(sum / static_cast<double>(s.size()));
}

}  // namespace

int main(int argc, char** argv) try {
  CLI::App app{"tachi-voice-eval: detection rate and false alarms of the voice keyword spotter (docs/voice.md)"};
  app.name("tachi-voice-eval");
  VoiceConfig commands;
  std::optional<double> threshold;
  std::optional<double> phone_loop;
  app.add_option("--phone-loop-probability", phone_loop, "pocketsphinx's -kws_plp, e.g. 1e-6 (default: the config's, 0.1)")
      ->check(CLI::Range(1e-300, 1.0));
  app.add_option("threshold", threshold, "kws threshold for both default phrases, e.g. 1e-30 (default: the config's)")
      ->check(CLI::Range(1e-100, 1.0));
  if (const int rc = tachi::common::parse(app, argc, argv); rc >= 0) return rc;
  if (threshold) for (auto& p : commands.phrases) p.threshold = *threshold;
  if (phone_loop) commands.phone_loop_probability = *phone_loop;
  std::printf("default phrases at thresholds %g / %g, phone-loop probability %g\n", commands.phrases[0].threshold,
              commands.phrases[1].threshold, commands.phone_loop_probability);
  const auto t0 = std::chrono::steady_clock::now();
  std::printf("%-58s %5s %8s %8s %6s %7s %8s\n", "group", "cmds", "detected", "rate", "wrong", "f.alarm", "audio_s");

  // 1. Real speech.
  {
    Tally real;
    VoiceConfig go;
    set_phrase(go, VoiceCommand::Start, "go forward");
    const auto goforward = read_raw_file(fixture::kTestData + "/goforward.raw");
    const auto found = spot_commands(go, goforward.samples);
    score({{"go forward", 0.0, static_cast<double>(goforward.samples.size()) / kVoiceSampleRate}}, found, real);
    real.audio_s += static_cast<double>(goforward.samples.size()) / kVoiceSampleRate;
    VoiceConfig cards;
    cards.phrases = {{"of clubs", VoiceCommand::Start, 1e-20}, {"of spades", VoiceCommand::Stop, 1e-20},
                     {"of hearts", VoiceCommand::Stop, 1e-20}};
    // cards.transcription: 001 "ten of clubs", 002 "four queen of clubs", 003 "seven of clubs",
    // 004 "five five", 005 "eight of spades four of clubs seven of hearts". Order is checked, not timing.
    const std::map<std::string, std::vector<std::string>> expected{{"001", {"of clubs"}},
                                                                   {"002", {"of clubs"}},
                                                                   {"003", {"of clubs"}},
                                                                   {"004", {}},
                                                                   {"005", {"of spades", "of clubs", "of hearts"}}};
    for (const auto& [id, phrases] : expected) {
      const auto audio = read_wav_file(fixture::kTestData + "/cards/" + id + ".wav");
      real.audio_s += static_cast<double>(audio.samples.size()) / kVoiceSampleRate;
      const auto got = spot_commands(cards, audio.samples);
      // In-order match of expected phrases against detections.
      std::size_t j = 0;
      for (const auto& d : got) {
        if (j < phrases.size() && d.phrase == phrases[j]) {
          ++real.detected;
          ++j;
        } else {
          ++real.false_alarms;
        }
      }
      real.commands += static_cast<int>(phrases.size());
    }
    print("real speech: goforward + cards (two-word phrases)", real);

    Tally libri;
    for (const auto& clip : fixture::librivox_clips()) {
      const auto audio = read_wav_file(clip);
      libri.audio_s += static_cast<double>(audio.samples.size()) / kVoiceSampleRate;
      libri.false_alarms += static_cast<int>(spot_commands(commands, audio.samples).size());
    }
    print("real speech: LibriVox reading, default phrases", libri);
  }

  // 2. Synthesised commands in varied sequences.
  std::vector<std::vector<std::int16_t>> librivox;
  for (const auto& clip : fixture::librivox_clips()) librivox.push_back(read_wav_file(clip).samples);
  const std::vector<std::pair<std::string, int>> voices{{"slt", 16}, {"awb", 4}, {"rms", 4}, {"kal16", 4}, {"kal", 4}};
  const std::vector<double> noise_snr_db{99, 30, 20, 10};  // 99: no noise; dB against the voice at gain 1
  Tally all_slt;
  for (const auto& [voice, sequences] : voices) {
    std::map<std::pair<std::string, double>, std::vector<std::int16_t>> said;
    for (const std::string phrase : {"start cutting", "stop cutting"})
      for (double stretch : {0.85, 1.0, 1.2}) said[{phrase, stretch}] = fixture::flite_say(phrase, stretch, voice);
    const double speech_rms = rms(said[{"start cutting", 1.0}]);
    std::map<double, Tally> by_noise;
    Tally voice_tally;
    for (int n = 0; n < sequences; ++n) {
      std::mt19937 rng{static_cast<unsigned>(1000 + n)};
      const double snr = noise_snr_db[static_cast<std::size_t>(n) % noise_snr_db.size()];
      const bool with_reading = (n / 4) % 2 == 1;  // every noise level with and without reading
      fixture::Sequence seq{static_cast<unsigned>(n + 1)};
      std::uniform_real_distribution<double> pause(0.3, 1.5), gain(0.5, 1.0);
      std::uniform_int_distribution<int> stretch_i(0, 2), clip_i(0, static_cast<int>(librivox.size()) - 1);
      seq.pause(pause(rng));
      for (int c = 0; c < 6; ++c) {
        const std::string phrase = c % 2 == 0 ? "start cutting" : "stop cutting";
        const double stretch = std::array{0.85, 1.0, 1.2}[static_cast<std::size_t>(stretch_i(rng))];
        seq.say(phrase, said[{phrase, stretch}], gain(rng));
        seq.pause(pause(rng));
        if (with_reading) {
          seq.add(librivox[static_cast<std::size_t>(clip_i(rng))]);
          seq.pause(pause(rng));
        }
      }
      if (snr < 99) seq.noise(speech_rms * std::pow(10.0, -snr / 20.0));
      Tally t;
      score(seq.placed(), spot_commands(commands, seq.samples()), t);
      t.audio_s = seq.seconds();
      for (Tally* sum : {&by_noise[snr], &voice_tally}) {
        sum->commands += t.commands;
        sum->detected += t.detected;
        sum->wrong_command += t.wrong_command;
        sum->false_alarms += t.false_alarms;
        sum->audio_s += t.audio_s;
      }
    }
    char label[96];
    std::snprintf(label, sizeof label, "flite %s, %d sequences (half amid LibriVox)", voice.c_str(), sequences);
    print(label, voice_tally);
    for (const auto& [snr, t] : by_noise) {
      std::snprintf(label, sizeof label, "  %s, SNR %s", voice.c_str(), snr >= 99 ? "clean" : (std::to_string(static_cast<int>(snr)) + " dB").c_str());
      print(label, t);
    }
  }
  std::printf("wall time %.1f s\n", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "tachi-voice-eval: %s\n", e.what());
  return 1;
}
