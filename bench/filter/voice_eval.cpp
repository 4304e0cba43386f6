// Voice command evaluation: detection rate and false alarms of the keyword spotter.
//  1. Real speech (pocketsphinx-testdata): goforward.raw ("go forward ten meters") with "go forward", and the
//     cards recordings with the two-word phrases "of clubs" / "of spades" / "of hearts"; LibriVox reading
//     (ordinary speech) with the default phrases for false alarms.
//  2. Synthesised commands: flite voices saying "start cutting" / "stop cutting" at three speaking rates,
//     in sequences of 6 alternating commands with random pauses (0.3-1.5 s), gains (0.5-1) and noise (clean,
//     30, 20, 10 dB SNR; white, or babble of LibriVox talkers), half of them interleaved with LibriVox
//     reading. No recording of a person saying the default phrases exists here.
// With --verify-sweep the second pass (keyword verification) is run with no threshold and the
// detections are scored again at each threshold of a grid: one decoding for the whole sweep.
// Prints counts per group; docs/benchmarks.md ("Filter and voice") records a run.
#include "tachi/sensor/voice_spotter.hpp"
#include "tachi/common/app.hpp"
#include "voice_fixture.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <random>

namespace {

using namespace tachi::sensor;
namespace fixture = tachi::sensor::testing;

constexpr double kLatencyS = 1.0;  // how long after an utterance its detection may come

struct Tally {
  int commands = 0;
  int detected = 0;       // right phrase, during or just after the utterance
  int wrong_command = 0;  // the other phrase at that time
  int false_alarms = 0;   // detections matching no utterance
  double audio_s = 0;

  Tally& operator+=(const Tally& o) {
    commands += o.commands;
    detected += o.detected;
    wrong_command += o.wrong_command;
    false_alarms += o.false_alarms;
    audio_s += o.audio_s;
    return *this;
  }
};

/// One decoded stretch of audio and what should have been found in it.
struct Run {
  std::string group;                  // row of the table it counts in
  std::vector<fixture::Placed> placed;  // timed utterances (synthesised sequences)
  std::optional<std::vector<std::string>> in_order;  // or: the phrases expected in this order (real speech)
  std::vector<VoiceDetection> found;
  double audio_s = 0;
};

/// Matches detections to placed utterances: a detection counts for an utterance when it is reported
/// between the utterance's start and 1 s after its end (0.6 s before the second pass, which waits for
/// 0.6 s of audio after a keyword hit before it judges it).
void score_timed(const std::vector<fixture::Placed>& placed, const std::vector<VoiceDetection>& found, Tally& t,
                 std::vector<bool>* matched = nullptr) {
  std::vector<bool> used(found.size(), false), right(found.size(), false);
  for (const auto& p : placed) {
    ++t.commands;
    bool hit = false, wrong = false;
    for (std::size_t i = 0; i < found.size(); ++i) {
      if (used[i] || found[i].time_s < p.begin_s || found[i].time_s > p.end_s + kLatencyS) continue;
      used[i] = true;
      right[i] = found[i].phrase == p.phrase;
      (right[i] ? hit : wrong) = true;
    }
    t.detected += hit ? 1 : 0;
    t.wrong_command += (!hit && wrong) ? 1 : 0;
  }
  for (bool u : used) t.false_alarms += u ? 0 : 1;
  if (matched != nullptr) *matched = right;
}

/// Real speech: the expected phrases in order, timing unchecked; anything else is a false alarm.
void score_in_order(const std::vector<std::string>& expected, const std::vector<VoiceDetection>& found, Tally& t) {
  std::size_t j = 0;  // expected phrases before j are matched or passed over (missed)
  for (const auto& d : found) {
    const auto next = std::find(expected.begin() + static_cast<std::ptrdiff_t>(j), expected.end(), d.phrase);
    if (next != expected.end()) {
      ++t.detected;
      j = static_cast<std::size_t>(next - expected.begin()) + 1;
    } else {
      ++t.false_alarms;
    }
  }
  t.commands += static_cast<int>(expected.size());
}

/// The runs' tallies per group, counting only detections whose second-pass score reaches `min_score`.
std::map<std::string, Tally> tally(const std::vector<Run>& runs, double min_score) {
  std::map<std::string, Tally> by_group;
  for (const auto& r : runs) {
    std::vector<VoiceDetection> kept;
    for (const auto& d : r.found)
      if (std::isnan(d.verification_score) || d.verification_score >= min_score) kept.push_back(d);
    Tally t;
    if (r.in_order)
      score_in_order(*r.in_order, kept, t);
    else
      score_timed(r.placed, kept, t);
    t.audio_s = r.audio_s;
    by_group[r.group] += t;
  }
  return by_group;
}

void print(const std::string& group, const Tally& t) {
  std::printf("%-58s %5d %8d %7.1f%% %6d %7d %8.1f\n", group.c_str(), t.commands, t.detected,
              t.commands ? 100.0 * t.detected / t.commands : 0.0, t.wrong_command, t.false_alarms, t.audio_s);
}

double rms(const std::vector<std::int16_t>& s) {
  double sum = 0;
  for (auto v : s) sum += static_cast<double>(v) * v;
  return std::sqrt(sum / static_cast<double>(s.size()));
}

std::string snr_label(double snr) { return snr >= 99 ? "clean" : std::to_string(static_cast<int>(snr)) + " dB"; }

}  // namespace

int main(int argc, char** argv) try {
  CLI::App app{"tachi-voice-eval: detection rate and false alarms of the voice keyword spotter (docs/voice.md)"};
  app.name("tachi-voice-eval");
  VoiceConfig commands;
  std::optional<double> threshold;
  std::optional<double> phone_loop;
  std::optional<double> verify;
  bool sweep = false;
  bool no_verify = false;
  bool show = false;
  unsigned seed_offset = 0;
  std::string noise = "white";
  app.add_option("--phone-loop-probability", phone_loop, "pocketsphinx's -kws_plp, e.g. 1e-6 (default: the config's)")
      ->check(CLI::Range(1e-300, 1.0));
  app.add_option("--verify", verify, "second pass: minimum log-likelihood ratio per frame (default: the config's)");
  app.add_flag("--no-verify", no_verify, "no second pass: every keyword hit is a command");
  app.add_flag("--verify-sweep", sweep, "run the second pass without a threshold and score a grid of thresholds");
  app.add_flag("--show-detections", show, "list every detection of the sequences with its second-pass score");
  app.add_option("--seed-offset", seed_offset, "added to the sequences' random seeds (0: the set the defaults were chosen on)");
  app.add_option("--noise", noise, "noise mixed into the sequences: white or babble (4 LibriVox talkers)")
      ->check(CLI::IsMember({"white", "babble"}));
  app.add_option("threshold", threshold, "kws threshold for both default phrases, e.g. 1e-30 (default: the config's)")
      ->check(CLI::Range(1e-100, 1.0));
  if (const int rc = tachi::common::parse(app, argc, argv); rc >= 0) return rc;
  if (threshold) for (auto& p : commands.phrases) p.threshold = *threshold;
  if (phone_loop) commands.phone_loop_probability = *phone_loop;
  if (verify) commands.verify_min_log_ratio = *verify;
  if (no_verify) commands.verify_min_log_ratio.reset();
  if (sweep) commands.verify_min_log_ratio = -std::numeric_limits<double>::infinity();
  char second_pass[48] = "off";
  if (sweep)
    std::snprintf(second_pass, sizeof second_pass, "swept");
  else if (commands.verify_min_log_ratio)
    std::snprintf(second_pass, sizeof second_pass, "min log ratio %g", *commands.verify_min_log_ratio);
  std::printf("default phrases at thresholds %g / %g, phone-loop probability %g, second pass %s, %s noise, seeds +%u\n",
              commands.phrases[0].threshold, commands.phrases[1].threshold, commands.phone_loop_probability, second_pass,
              noise.c_str(), seed_offset);
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<Run> runs;
  const auto with_verification = [&](VoiceConfig c) {
    c.verify_min_log_ratio = commands.verify_min_log_ratio;
    c.phone_loop_probability = commands.phone_loop_probability;
    return c;
  };

  // 1. Real speech.
  const std::string real_group = "real speech: goforward + cards (two-word phrases)";
  {
    VoiceConfig go = with_verification(VoiceConfig{});
    set_phrase(go, VoiceCommand::Start, "go forward");
    const auto goforward = read_raw_file(fixture::kTestData + "/goforward.raw");
    runs.push_back({real_group, {}, std::vector<std::string>{"go forward"}, spot_commands(go, goforward.samples),
                    static_cast<double>(goforward.samples.size()) / kVoiceSampleRate});
    VoiceConfig cards = with_verification(VoiceConfig{});
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
      runs.push_back({real_group, {}, phrases, spot_commands(cards, audio.samples),
                      static_cast<double>(audio.samples.size()) / kVoiceSampleRate});
    }
    for (const auto& clip : fixture::librivox_clips()) {
      const auto audio = read_wav_file(clip);
      runs.push_back({"real speech: LibriVox reading, default phrases", {}, std::vector<std::string>{},
                      spot_commands(commands, audio.samples), static_cast<double>(audio.samples.size()) / kVoiceSampleRate});
    }
  }

  // 2. Synthesised commands in varied sequences.
  std::vector<std::vector<std::int16_t>> librivox;
  for (const auto& clip : fixture::librivox_clips()) librivox.push_back(read_wav_file(clip).samples);
  const std::vector<std::pair<std::string, int>> voices{{"slt", 16}, {"awb", 4}, {"rms", 4}, {"kal16", 4}, {"kal", 4}};
  const std::vector<double> noise_snr_db{99, 30, 20, 10};  // 99: no noise; dB against the voice at gain 1
  std::vector<std::string> group_order{real_group, "real speech: LibriVox reading, default phrases"};
  for (const auto& [voice, sequences] : voices) {
    std::map<std::pair<std::string, double>, std::vector<std::int16_t>> said;
    for (const std::string phrase : {"start cutting", "stop cutting"})
      for (double stretch : {0.85, 1.0, 1.2}) said[{phrase, stretch}] = fixture::flite_say(phrase, stretch, voice);
    const double speech_rms = rms(said[{"start cutting", 1.0}]);
    for (double snr : noise_snr_db) group_order.push_back(voice + ", SNR " + snr_label(snr));
    for (int n = 0; n < sequences; ++n) {
      std::mt19937 rng{static_cast<unsigned>(1000 + n) + seed_offset};
      const double snr = noise_snr_db[static_cast<std::size_t>(n) % noise_snr_db.size()];
      const bool with_reading = (n / 4) % 2 == 1;  // every noise level with and without reading
      fixture::Sequence seq{static_cast<unsigned>(n + 1) + seed_offset};
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
      const double noise_rms = speech_rms * std::pow(10.0, -snr / 20.0);
      if (snr < 99) {
        if (noise == "babble")
          seq.babble(librivox, 4, noise_rms);
        else
          seq.noise(noise_rms);
      }
      runs.push_back({voice + ", SNR " + snr_label(snr), seq.placed(), std::nullopt, spot_commands(commands, seq.samples()),
                      seq.seconds()});
    }
  }

  // Summary rows over the 16 kHz voices (kal is an 8 kHz voice: never recognised, not counted).
  const auto summary = [&](const std::map<std::string, Tally>& by_group, const std::string& snr) {
    Tally t;
    for (const std::string voice : {"slt", "awb", "rms", "kal16"}) t += by_group.count(voice + ", SNR " + snr) ? by_group.at(voice + ", SNR " + snr) : Tally{};
    return t;
  };
  const auto synthesised_false_alarms = [&](const std::map<std::string, Tally>& by_group) {
    int n = 0;
    for (const auto& [group, t] : by_group)
      if (group.rfind("real", 0) != 0) n += t.false_alarms + t.wrong_command;
    return n;
  };
  if (show)
    for (const auto& r : runs) {
      if (r.in_order) continue;
      Tally ignored;
      std::vector<bool> matched;
      score_timed(r.placed, r.found, ignored, &matched);
      for (std::size_t i = 0; i < r.found.size(); ++i) {
        // The utterance said nearest before the detection, to tell a late or mislabelled hit from a false alarm.
        std::string said = "-";
        for (const auto& p : r.placed)
          if (p.begin_s <= r.found[i].time_s) said = p.phrase + " " + std::to_string(p.begin_s).substr(0, 6) + "-" + std::to_string(p.end_s).substr(0, 6);
        std::printf("detection %-22s %8.3f s %-14s %-5s score %7.2f (last said: %s)\n", r.group.c_str(), r.found[i].time_s,
                    r.found[i].phrase.c_str(), matched[i] ? "hit" : "FALSE", r.found[i].verification_score, said.c_str());
      }
    }
  if (!sweep) {
    const auto by_group = tally(runs, -std::numeric_limits<double>::infinity());
    std::printf("%-58s %5s %8s %8s %6s %7s %8s\n", "group", "cmds", "detected", "rate", "wrong", "f.alarm", "audio_s");
    for (const auto& g : group_order) print(g, by_group.at(g));
    for (const std::string snr : {"clean", "30 dB", "20 dB", "10 dB"}) print("16 kHz voices (slt awb rms kal16), SNR " + snr, summary(by_group, snr));
  } else {
    std::printf("%9s %9s %9s %10s %10s %10s %10s %10s %9s\n", "min_score", "real", "libri.fa", "clean", "30 dB", "20 dB", "slt 20 dB",
                "10 dB", "synth.fa");
    std::vector<double> grid;
    for (double s = -40; s <= 10; s += 2) grid.push_back(s);
    grid.insert(grid.begin(), -std::numeric_limits<double>::infinity());
    for (double s : grid) {
      const auto g = tally(runs, s);
      const auto cell = [](const Tally& t) { return std::to_string(t.detected) + "/" + std::to_string(t.commands); };
      std::printf("%9.1f %6s+%-2d %9d %10s %10s %10s %10s %10s %9d\n", s, cell(g.at(real_group)).c_str(), g.at(real_group).false_alarms,
                  g.at("real speech: LibriVox reading, default phrases").false_alarms, cell(summary(g, "clean")).c_str(),
                  cell(summary(g, "30 dB")).c_str(), cell(summary(g, "20 dB")).c_str(), cell(g.at("slt, SNR 20 dB")).c_str(),
                  cell(summary(g, "10 dB")).c_str(), synthesised_false_alarms(g));
    }
  }
  std::printf("wall time %.1f s\n", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "tachi-voice-eval: %s\n", e.what());
  return 1;
}
