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
#include "paths.hpp"
#include "tachi/sensor/voice_spotter.hpp"
#include "tachi/common/app.hpp"
#include "voice_fixture.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <atomic>
#include <mutex>
#include <numeric>
#include <span>
#include <thread>

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

// ---- Across speakers -------------------------------------------------------------------------------
// Every English voice the machine synthesises (espeak-ng en and en-us with their +m1..m7 / +f1..f5
// variants, flite kal kal16 awb rms slt, festival kal and slt), each also pitch-shifted and
// tempo-changed with sox, in six conditions (clean, white noise and LibriVox babble at 20 and 10 dB,
// room reverb), the two commands said alone and inside sentences, start then stop 2 s apart. Plus
// false alarms on LibriVox reading and babble with no command in it.

/// Base voices; `tune` says whether the thresholds were chosen on it (the rest are held out).
struct BaseVoice {
  fixture::Speaker speaker;
  bool tune;
};
std::vector<BaseVoice> base_voices() {
  std::vector<BaseVoice> v;
  // Tuning set: half of each family, alternating, so that every kind of voice is on both sides.
  const std::vector<std::string> variants{"", "+m1", "+m2", "+m3", "+m4", "+m5", "+m6", "+m7", "+f1", "+f2", "+f3", "+f4", "+f5"};
  for (const std::string lang : {"en-us", "en"})
    for (std::size_t i = 0; i < variants.size(); ++i)
      v.push_back({{"espeak-ng", lang + variants[i]}, (i % 2 == 0) == (lang == "en-us")});
  // flite's rms (the voice of the reported start/stop swap) and festival's slt are held out.
  for (const auto& [voice, tune] : std::vector<std::pair<std::string, bool>>{{"slt", true}, {"awb", true}, {"rms", false}, {"kal16", false}, {"kal", false}})
    v.push_back({{"flite", voice}, tune});
  v.push_back({{"festival", "voice_kal_diphone"}, true});
  v.push_back({{"festival", "voice_cmu_us_slt_arctic_hts"}, false});
  return v;
}

struct Condition {
  std::string name;
  std::string noise;  // "", "white", "babble"
  double snr_db = 0;
  bool reverb = false;
};
const std::vector<Condition> kConditions{{"clean", "", 0, false},        {"white 20 dB", "white", 20, false},
                                         {"white 10 dB", "white", 10, false}, {"babble 20 dB", "babble", 20, false},
                                         {"babble 10 dB", "babble", 10, false}, {"reverb", "", 0, true}};

std::string family_of(const fixture::Speaker& s) {
  if (s.engine == "espeak-ng") return s.voice.rfind("en-us", 0) == 0 ? "espeak-ng en-us" : "espeak-ng en";
  return s.engine;
}

/// One sequence of a speaker: what was said where, what the spotter reported (scores kept, so that
/// thresholds can be applied afterwards: one decoding for a whole sweep).
struct SpeakerRun {
  std::string family, variant, condition, context;
  bool tune_voice = false;
  std::vector<fixture::Placed> placed;
  std::vector<VoiceDetection> found;
  double audio_s = 0;
};

struct SpeakerSet {
  std::string name;  // tune, heldout, all, ci
  unsigned seed_base = 0;
};

/// Synthesises and decodes every sequence of one speaker through one spotter (a continuous stream,
/// as a microphone's: sequences follow each other, each ending in 1.5 s of its own noise so that the
/// second pass judges its last command on its own audio).
std::vector<SpeakerRun> run_speaker(const VoiceConfig& config, const fixture::Speaker& speaker, const std::string& variant, bool tune_voice,
                                    const std::vector<Condition>& conditions, const std::vector<std::string>& contexts, unsigned seed,
                                    const std::vector<std::vector<std::int16_t>>& librivox, const std::string& cache) {
  const auto phrase_of = [&](VoiceCommand c) {
    return std::find_if(config.phrases.begin(), config.phrases.end(), [&](const VoicePhrase& p) { return p.command == c; })->phrase;
  };
  const std::string start = phrase_of(VoiceCommand::Start), stop = phrase_of(VoiceCommand::Stop);
  KeywordSpotter spotter{config, true};  // every verdict: the thresholds are applied when scoring
  std::vector<SpeakerRun> runs;
  std::mt19937 rng{seed};
  const std::array<std::string, 2> start_carriers{"okay %s now", "now %s along the line"};
  const std::array<std::string, 2> stop_carriers{"alright %s please", "that is enough, %s"};
  for (const auto& condition : conditions)
    for (const auto& context : contexts) {
      std::uniform_real_distribution<double> lead(0.4, 1.0), gain(0.6, 1.0);
      std::uniform_int_distribution<int> carrier(0, 1);
      const auto text = [&](const std::string& phrase, const std::array<std::string, 2>& carriers) {
        if (context == "alone") return phrase;
        std::string t = carriers[static_cast<std::size_t>(carrier(rng))];
        return t.replace(t.find("%s"), 2, phrase);
      };
      const auto said_start = fixture::synthesize(speaker, text(start, start_carriers), condition.reverb, cache);
      const auto said_stop = fixture::synthesize(speaker, text(stop, stop_carriers), condition.reverb, cache);
      fixture::Sequence seq{static_cast<unsigned>(rng())};
      seq.pause(lead(rng));
      seq.say(start, said_start, gain(rng));
      seq.pause(2.0);  // the reported swap: "stop cutting" 2 s after "start cutting"
      seq.say(stop, said_stop, gain(rng));
      seq.pause(1.5);
      if (!condition.noise.empty()) {
        // SNR against the speech at full gain, over the utterance (synthesisers pad little silence).
        const double noise_rms = rms(said_start) * std::pow(10.0, -condition.snr_db / 20.0);
        if (condition.noise == "white")
          seq.noise(noise_rms);
        else
          seq.babble(librivox, 4, noise_rms);
      }
      SpeakerRun run{family_of(speaker), variant, condition.name, context, tune_voice, seq.placed(), {}, seq.seconds()};
      const double t0 = spotter.time_s();
      constexpr std::size_t kBlock = 512;
      const auto& s = seq.samples();
      for (std::size_t at = 0; at < s.size(); at += kBlock)
        for (auto d : spotter.process(std::span(s).subspan(at, std::min(kBlock, s.size() - at)))) {
          d.time_s -= t0;
          run.found.push_back(d);
        }
      runs.push_back(std::move(run));
    }
  for (auto d : spotter.finish()) {  // nothing should be pending after the last 1.5 s pause
    d.time_s = runs.back().audio_s;
    runs.back().found.push_back(d);
  }
  return runs;
}

/// Thresholds applied after decoding (the spotter ran with none).
struct Gate {
  VoiceConfig thresholds;  // the verify_* thresholds applied (verification_accepts, as the spotter does)
  bool keeps(const VoiceDetection& d) const { return std::isnan(d.verification_score) || verification_accepts(thresholds, d); }
  Gate with(double min_log_ratio, double min_margin) const {
    Gate g = *this;
    g.thresholds.verify_min_log_ratio = min_log_ratio;
    g.thresholds.verify_min_margin = min_margin;
    return g;
  }
};

struct SpeakerTally {
  int commands = 0, found = 0, wrong = 0, false_alarms = 0;
  double audio_s = 0;
  SpeakerTally& operator+=(const SpeakerTally& o) {
    commands += o.commands, found += o.found, wrong += o.wrong, false_alarms += o.false_alarms, audio_s += o.audio_s;
    return *this;
  }
};

/// A detection counts for an utterance when it comes between its start and 1 s after its end: found
/// when it names the utterance's command, WRONG when it names another (even beside a right one).
/// Detections near no utterance are false alarms.
SpeakerTally score(const SpeakerRun& run, const Gate& gate, const VoiceConfig& config) {
  SpeakerTally t;
  t.audio_s = run.audio_s;
  const auto command_of = [&](const std::string& phrase) {
    return std::find_if(config.phrases.begin(), config.phrases.end(), [&](const VoicePhrase& p) { return p.phrase == phrase; })->command;
  };
  std::vector<bool> used(run.found.size(), false);
  for (const auto& p : run.placed) {
    ++t.commands;
    bool right = false, wrong = false;
    for (std::size_t i = 0; i < run.found.size(); ++i) {
      const auto& d = run.found[i];
      if (!gate.keeps(d) || d.time_s < p.begin_s || d.time_s > p.end_s + kLatencyS) continue;
      used[i] = true;
      (d.command == command_of(p.phrase) ? right : wrong) = true;
    }
    t.found += right ? 1 : 0;
    t.wrong += wrong ? 1 : 0;
  }
  for (std::size_t i = 0; i < run.found.size(); ++i) t.false_alarms += (!used[i] && gate.keeps(run.found[i])) ? 1 : 0;
  return t;
}

/// Commands said nowhere: LibriVox reading (the five clips alone, then in random orders, gains and
/// pauses, with white noise at 20-40 dB) and babble (four of the clips at once from random points).
/// Returns one run a chunk of ~30 s, context "librivox" or "babble".
std::vector<SpeakerRun> run_no_commands(const VoiceConfig& config, const std::string& corpus, double seconds, unsigned seed,
                                        const std::vector<std::vector<std::int16_t>>& librivox) {
  KeywordSpotter spotter{config, true};  // every verdict: the thresholds are applied when scoring
  std::vector<SpeakerRun> runs;
  std::mt19937 rng{seed};
  const auto decode = [&](const std::vector<std::int16_t>& s) {
    SpeakerRun run{corpus, "-", "-", corpus, false, {}, {}, static_cast<double>(s.size()) / kVoiceSampleRate};
    for (std::size_t at = 0; at < s.size(); at += 512)
      for (const auto& d : spotter.process(std::span(s).subspan(at, std::min<std::size_t>(512, s.size() - at)))) run.found.push_back(d);
    runs.push_back(std::move(run));
  };
  double total = 0;
  if (corpus == "librivox")
    for (const auto& clip : librivox) {
      decode(clip);
      total += runs.back().audio_s;
    }
  while (total < seconds) {
    fixture::Sequence seq{static_cast<unsigned>(rng())};
    if (corpus == "librivox") {
      std::uniform_real_distribution<double> pause(0.2, 1.0), gain(0.5, 1.0), snr(20, 40);
      std::vector<std::size_t> order(librivox.size());
      std::iota(order.begin(), order.end(), 0);
      std::shuffle(order.begin(), order.end(), rng);
      for (auto i : order) {
        seq.pause(pause(rng));
        seq.say("-", librivox[i], gain(rng));
      }
      seq.noise(rms(librivox[0]) * std::pow(10.0, -snr(rng) / 20.0));
    } else {
      seq.pause(30.0);
      seq.babble(librivox, 4, std::uniform_real_distribution<double>(1000, 4000)(rng));
    }
    decode(seq.samples());
    total += runs.back().audio_s;
  }
  for (const auto& d : spotter.finish()) runs.back().found.push_back(d);
  return runs;
}

int speakers_main(VoiceConfig config, const std::string& set, unsigned seed_offset, int threads, double no_command_s,
                  const std::string& cache, std::optional<std::pair<double, double>> sweep_ratio, bool check,
                  const std::vector<std::string>& only_conditions, const std::vector<std::string>& only_contexts,
                  const std::vector<std::string>& only_variants, const std::vector<std::string>& only_voices, const std::string& dump,
                  bool first_word_sweep) {
  const Gate gate{config};
  // The spotters report every verdict, refused ones too: the thresholds are applied when scoring (a sweep
  // needs one decoding only). They decode with the config's thresholds, since with several warps those
  // decide whether the warped lanes judge an utterance (only where the unwarped lane gives no command):
  // a sweep's other thresholds are applied to the verdicts the config's chose.
  std::vector<std::vector<std::int16_t>> librivox;
  for (const auto& clip : fixture::librivox_clips()) librivox.push_back(read_wav_file(clip).samples);
  // Jobs: every speaker (base voice, pitch-shifted, tempo-changed) of the set, then the corpora
  // without commands. The shifts are drawn per voice from the set's seeds.
  struct Job {
    fixture::Speaker speaker;
    std::string variant;
    bool tune_voice;
    unsigned seed;
  };
  std::vector<Job> jobs;
  std::vector<Condition> conditions = kConditions;
  std::vector<std::string> contexts{"alone", "sentence"};
  const unsigned seed_base = (set == "heldout" ? 5000U : 0U) + seed_offset;
  const auto voices = base_voices();
  for (std::size_t v = 0; v < voices.size(); ++v) {
    const auto& [speaker, tune] = voices[v];
    if ((set == "tune" && !tune) || (set == "heldout" && tune)) continue;
    if (set == "ci" && !(speaker.voice == "en+m3" || speaker.voice == "en-us+f2" || speaker.voice == "rms" ||
                         speaker.voice == "voice_cmu_us_slt_arctic_hts"))
      continue;
    std::mt19937 rng{seed_base + 100U * static_cast<unsigned>(v)};
    // Pitch: 2-5 semitones up or down; tempo: 0.75-0.9 or 1.12-1.3 (sox keeps the other).
    // sox's pitch moves the formants with the pitch, as a longer or shorter vocal tract would: 1.5-3.5
    // semitones, about the spread of adult vocal tract lengths (women's ~15-20 % shorter than men's:
    // ~3 semitones). Up for every other voice, down for the others; faster or slower likewise.
    const int cents = std::uniform_int_distribution<int>(150, 350)(rng) * (v % 2 == 0 ? 1 : -1);
    const double tempo = (v / 2) % 2 == 0 ? std::uniform_real_distribution<double>(0.75, 0.9)(rng) : std::uniform_real_distribution<double>(1.12, 1.3)(rng);
    auto pitched = speaker, timed = speaker;
    pitched.pitch_cents = cents;
    timed.tempo = std::round(tempo * 100) / 100;
    jobs.push_back({speaker, "as synthesised", tune, seed_base + 100U * static_cast<unsigned>(v) + 1});
    jobs.push_back({pitched, "pitch-shifted", tune, seed_base + 100U * static_cast<unsigned>(v) + 2});
    if (set != "ci") jobs.push_back({timed, "tempo-changed", tune, seed_base + 100U * static_cast<unsigned>(v) + 3});
  }
  if (set == "ci") {
    conditions = {kConditions[0], kConditions[1], kConditions[4], kConditions[5]};
    contexts = {"alone"};
  }
  if (!only_conditions.empty())
    std::erase_if(conditions, [&](const Condition& c) { return std::find(only_conditions.begin(), only_conditions.end(), c.name) == only_conditions.end(); });
  if (!only_contexts.empty()) contexts = only_contexts;
  if (!only_variants.empty())
    std::erase_if(jobs, [&](const Job& j) { return std::find(only_variants.begin(), only_variants.end(), j.variant) == only_variants.end(); });
  // One voice's jobs keep the seeds they have in the whole set: the same audio (each voice's conditions and
  // contexts draw from one generator, so --conditions and --contexts change the audio; --voices does not).
  if (!only_voices.empty())
    std::erase_if(jobs, [&](const Job& j) { return std::find(only_voices.begin(), only_voices.end(), j.speaker.voice) == only_voices.end(); });
  std::vector<std::vector<SpeakerRun>> results(jobs.size() + 2);
  std::atomic<std::size_t> next{0};
  std::mutex log_mutex;
  const auto worker = [&] {
    for (std::size_t j; (j = next++) < results.size();) {
      if (j < jobs.size())
        results[j] = run_speaker(config, jobs[j].speaker, jobs[j].variant, jobs[j].tune_voice, conditions, contexts, jobs[j].seed, librivox, cache);
      else
        results[j] = run_no_commands(config, j == jobs.size() ? "librivox" : "babble", no_command_s, seed_base + 7U + static_cast<unsigned>(j), librivox);
      const std::lock_guard lock{log_mutex};
      std::fprintf(stderr, "\r%zu/%zu decoded", j + 1, results.size());
    }
  };
  std::vector<std::thread> pool;
  for (int i = 0; i < threads; ++i) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  std::fprintf(stderr, "\n");
  std::vector<SpeakerRun> runs;
  for (auto& r : results) runs.insert(runs.end(), r.begin(), r.end());

  if (!dump.empty()) {
    // Every run and every detection with its features, to choose gates offline (one decoding).
    std::FILE* f = std::fopen(dump.c_str(), "w");
    if (f == nullptr) throw std::runtime_error("cannot write --dump " + dump);
    for (std::size_t r = 0; r < runs.size(); ++r) {
      const auto& run = runs[r];
      std::fprintf(f, "R\t%zu\t%s\t%s\t%s\t%s\t%zu\t%.3f\n", r, run.family.c_str(), run.variant.c_str(), run.condition.c_str(),
                   run.context.c_str(), run.placed.size(), run.audio_s);
      for (const auto& d : run.found) {
        int utterance = -1;
        bool right = false;
        for (std::size_t u = 0; u < run.placed.size() && utterance < 0; ++u)
          if (d.time_s >= run.placed[u].begin_s && d.time_s <= run.placed[u].end_s + kLatencyS) {
            utterance = static_cast<int>(u);
            right = std::find_if(config.phrases.begin(), config.phrases.end(), [&](const VoicePhrase& p) {
                      return p.phrase == run.placed[u].phrase;
                    })->command == d.command;
          }
        std::fprintf(f, "D\t%zu\t%d\t%d\t%s\t%.3f\t%.3f\t%.3f\t%.3f\t%.3f\t%.3f\t%.3f\t%.3f\t%.2f\t%.2f\t%d\t%d", r, utterance,
                     right ? 1 : 0, d.phrase.c_str(), d.time_s, d.verification_score, d.command_margin, d.phrase_score, d.phrase_margin,
                     d.level_db, d.garbage_score, d.garbage_margin, d.phrase_duration_s, d.garbage_duration_s, d.unwarped_hit ? 1 : 0,
                     d.by_warps ? 1 : 0);
        // Where things lie (VoiceDetection::Alignment): the keyword hit's phrase and span, the window's
        // start, the phrase and its rival as the garbage grammar aligns them, and the utterance's span.
        // (The hit's phrase as its index in the config's phrases: every column after the phrase stays a number.)
        const auto hit_phrase = std::find_if(config.phrases.begin(), config.phrases.end(), [&](const VoicePhrase& p) { return p.phrase == d.hit_phrase; });
        std::fprintf(f, "\t%td\t%.3f\t%.3f\t%.3f", hit_phrase == config.phrases.end() ? -1 : hit_phrase - config.phrases.begin(), d.hit_begin_s,
                     d.hit_end_s, d.window_begin_s);
        for (const auto* a : {&d.aligned, &d.rival})
          std::fprintf(f, "\t%.3f\t%.3f\t%.3f\t%.3f\t%.3f\t%.3f", a->begin_s, a->first_word_end_s, a->end_s, a->first_word_ratio,
                       a->rest_ratio, a->garbage_score);
        std::fprintf(f, "\t%.3f\t%.3f\n", utterance >= 0 ? run.placed[static_cast<std::size_t>(utterance)].begin_s : -1.0,
                     utterance >= 0 ? run.placed[static_cast<std::size_t>(utterance)].end_s : -1.0);
      }
    }
    std::fclose(f);
  }
  const auto totals = [&](const Gate& g, auto&& key) {
    std::map<std::string, SpeakerTally> by;
    for (const auto& r : runs)
      if (const std::string k = key(r); !k.empty()) by[k] += score(r, g, config);
    return by;
  };
  const auto commanded = [](const SpeakerRun& r) { return r.context == "alone" || r.context == "sentence"; };
  const auto at_20 = [&](const SpeakerRun& r) { return commanded(r) && r.condition.find("20 dB") != std::string::npos; };
  if (sweep_ratio) {
    std::printf("%9s %7s %14s %14s %12s %8s %8s\n", "min_ratio", "margin", "20 dB alone", "20 dB all", "found all", "wrong", "fa/h");
    for (double ratio = sweep_ratio->first; ratio <= sweep_ratio->second + 1e-9; ratio += 2)
      for (double margin : {0.0, 1.0, 2.0, 3.0, 4.0, 6.0, 8.0}) {
        const Gate g = gate.with(ratio, margin);
        SpeakerTally a20, all20, all, none;
        for (const auto& r : runs) {
          const auto t = score(r, g, config);
          if (!commanded(r)) none += t;
          else {
            all += t;
            if (at_20(r)) (all20 += t, r.context == "alone" ? (a20 += t, 0) : 0);
          }
        }
        std::printf("%9.1f %7.1f %6d/%-4d%3.0f%% %6d/%-4d%3.0f%% %6d/%-5d %8d %8.2f\n", ratio, margin, a20.found, a20.commands,
                    100.0 * a20.found / std::max(1, a20.commands), all20.found, all20.commands, 100.0 * all20.found / std::max(1, all20.commands),
                    all.found, all.commands, all.wrong, 3600.0 * (none.false_alarms + all.false_alarms) / std::max(1.0, none.audio_s));
      }
  }
  std::printf("voices: %s set (seeds +%u), phrases \"%s\" / \"%s\", second pass: min log ratio %g, min margin %g\n", set.c_str(), seed_base,
              std::find_if(config.phrases.begin(), config.phrases.end(), [](const VoicePhrase& p) { return p.command == VoiceCommand::Start; })->phrase.c_str(),
              std::find_if(config.phrases.begin(), config.phrases.end(), [](const VoicePhrase& p) { return p.command == VoiceCommand::Stop; })->phrase.c_str(),
              gate.thresholds.verify_min_log_ratio.value_or(-std::numeric_limits<double>::infinity()), gate.thresholds.verify_min_margin);
  std::printf("second pass at the warps (VTLN):");
  for (const double w : config.warps) std::printf(" %g", w);
  if (config.warps.size() > 1) {
    // What the warped lanes add (they judge only where the unwarped lane gives no command).
    int kept = 0, found_by_warps = 0, without_unwarped_hit = 0;
    for (const auto& r : runs)
      for (const auto& d : r.found)
        if (d.by_warps && gate.keeps(d)) {
          ++kept;
          without_unwarped_hit += d.unwarped_hit ? 0 : 1;
          found_by_warps += score(SpeakerRun{r.family, r.variant, r.condition, r.context, r.tune_voice, r.placed, {d}, 0}, gate, config).found;
        }
    std::printf("; detections by the warped lanes %d (%d right; %d where the unwarped lane had no keyword hit)", kept, found_by_warps,
                without_unwarped_hit);
  }
  std::printf("\n");
  const auto table = [&](const std::string& title, auto&& key) {
    std::printf("\n| %s | commands | found | rate | WRONG | false alarms |\n|---|---|---|---|---|---|\n", title.c_str());
    for (const auto& [k, t] : totals(gate, key))
      std::printf("| %s | %d | %d | %.1f%% | %d | %d |\n", k.c_str(), t.commands, t.found, 100.0 * t.found / std::max(1, t.commands), t.wrong,
                  t.false_alarms);
  };
  table("condition, context", [&](const SpeakerRun& r) { return commanded(r) ? r.condition + ", " + r.context : std::string{}; });
  table("voices (all conditions)", [&](const SpeakerRun& r) { return commanded(r) ? r.family + ", " + r.variant : std::string{}; });
  table("voices at 20 dB (white and babble)", [&](const SpeakerRun& r) { return at_20(r) ? r.family + ", " + r.context : std::string{}; });
  const auto overall = totals(gate, [&](const SpeakerRun& r) {
    if (!commanded(r)) return r.context;
    return std::string(at_20(r) ? "20 dB" : "other");
  });
  const auto get = [&](const std::string& k) { return overall.count(k) ? overall.at(k) : SpeakerTally{}; };
  SpeakerTally all_commanded = get("20 dB");
  all_commanded += get("other");
  std::printf("\n| without commands | audio | false alarms | per hour |\n|---|---|---|---|\n");
  bool fa_ok = true;
  for (const std::string corpus : {"librivox", "babble"}) {
    const auto t = get(corpus);
    const double per_hour = 3600.0 * t.false_alarms / std::max(1.0, t.audio_s);
    fa_ok = fa_ok && per_hour <= 1.0;
    std::printf("| %s | %.0f s | %d | %.2f |\n", corpus == "librivox" ? "LibriVox reading" : "LibriVox babble (4 talkers)", t.audio_s, t.false_alarms, per_hour);
  }
  if (first_word_sweep) {
    // The first-word margin (VoiceConfig::verify_min_first_word_margin) at several thresholds on this one
    // decoding (the spotter reports refused verdicts too), the rest of the gates as the config's.
    std::printf("\n| first-word margin | found at 20 dB | found, all conditions | WRONG | false alarms amid the sequences | LibriVox | babble |\n"
                "|---|---|---|---|---|---|---|\n");
    std::vector<std::optional<double>> thresholds{std::nullopt};
    for (const double t : {-10.0, -6.0, -4.0, -3.0, -2.0, -1.0, 0.0, 1.0, 2.0, 3.0, 4.0, 6.0}) thresholds.emplace_back(t);
    for (const auto& t : thresholds) {
      Gate g = gate;
      g.thresholds.verify_min_first_word_margin = t;
      SpeakerTally at20, all, reading, babble;
      for (const auto& r : runs) {
        const auto s = score(r, g, config);
        if (commanded(r)) {
          all += s;
          if (at_20(r)) at20 += s;
        } else {
          (r.context == "librivox" ? reading : babble) += s;
        }
      }
      char name[32] = "off";
      if (t) std::snprintf(name, sizeof name, "%g", *t);
      std::printf("| %s | %d/%d | %d/%d | %d | %d | %d | %d |\n", name, at20.found, at20.commands, all.found,
                  all.commands, all.wrong, all.false_alarms, reading.false_alarms, babble.false_alarms);
    }
  }
  const auto t20 = get("20 dB");
  const double rate20 = 100.0 * t20.found / std::max(1, t20.commands);
  std::printf("\nacceptance: found at 20 dB %d/%d = %.1f%% (>= 90%%); WRONG commands %d over all conditions (0); false alarms amid the "
              "sequences %d; false alarms per hour above\n",
              t20.found, t20.commands, rate20, all_commanded.wrong, all_commanded.false_alarms);
  const bool ok = rate20 >= 90.0 && all_commanded.wrong == 0 && fa_ok;
  std::printf("%s\n", ok ? "PASS" : "FAIL");
  return check && !ok ? 1 : 0;
}

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
  app.add_option("--noise", noise, "noise mixed into the sequences: white (default) or babble (4 LibriVox talkers)")
      ->check(CLI::IsMember({"white", "babble"}));
  app.add_option("threshold", threshold, "kws threshold for both default phrases, e.g. 1e-30 (default: the config's)")
      ->check(CLI::Range(1e-100, 1.0));
  std::string speakers;
  std::string config_file = tachi::test::source_dir() + "/config/voice.json";
  std::string start_phrase, stop_phrase;
  std::optional<double> margin;
  int threads = 1;
  double no_command_s = 600;
  std::string cache = tachi::test::binary_dir() + "/voice-cache";
  std::vector<double> sweep_ratio;
  bool check = false;
  std::vector<std::string> only_conditions, only_contexts, only_variants;
  app.add_option("--conditions", only_conditions, "--speakers: only these conditions")
      ->check(CLI::IsMember({"clean", "white 20 dB", "white 10 dB", "babble 20 dB", "babble 10 dB", "reverb"}));
  app.add_option("--contexts", only_contexts, "--speakers: only these contexts")->check(CLI::IsMember({"alone", "sentence"}));
  app.add_option("--variants", only_variants, "--speakers: only these variants of the voices (the pitch-shifted ones are found least)")
      ->check(CLI::IsMember({"as synthesised", "pitch-shifted", "tempo-changed"}));
  std::vector<std::string> only_voices;
  app.add_option("--voices", only_voices,
                 "--speakers: only these voices of the set (espeak-ng en-us+m6, flite slt, festival voice_kal_diphone: the voice's name, "
                 "e.g. en-us+m6 or slt), with the audio they have in the whole set");
  app.add_option("--speakers", speakers,
                 "evaluate across speakers (docs/voice.md): every voice and condition of the set: tune (the thresholds were "
                 "chosen on it), heldout (the other voices, other seeds), all, ci (4 voices, 4 conditions: the ctest)")
      ->check(CLI::IsMember({"tune", "heldout", "all", "ci"}));
  app.add_option("--config", config_file, "--speakers: voice config (default: the shipped config/voice.json)")->check(CLI::ExistingFile);
  app.add_option("--start-phrase", start_phrase, "--speakers: the start phrase instead of the config's");
  app.add_option("--stop-phrase", stop_phrase, "--speakers: the stop phrase instead of the config's");
  app.add_option("--margin", margin, "--speakers: the second pass's minimum margin over another command (default: the config's)");
  app.add_option("--threads", threads, "--speakers: decoding threads (default 1)")->check(CLI::Range(1, 8));
  app.add_option("--no-command-seconds", no_command_s, "--speakers: seconds of LibriVox reading and of babble without commands, each (default 600)")
      ->check(CLI::Range(0.0, 36000.0));
  app.add_option("--cache", cache, "--speakers: folder for the synthesised audio (default: voice-cache in the build tree)");
  app.add_option("--sweep", sweep_ratio, "--speakers: sweep min log ratio FROM TO (step 2) x margins instead of the table")->expected(2);
  std::string dump;
  app.add_option("--dump", dump, "--speakers: write every run and detection with its second-pass features (tab-separated; the last two columns: whether the unwarped lane had a keyword hit on it, whether the warped lanes judged it) to this file");
  bool first_word_sweep = false;
  app.add_flag("--first-word-sweep", first_word_sweep,
               "--speakers: also score the first-word margin (verify_min_first_word_margin) at several thresholds, off to 6");
  app.add_flag("--check", check, "--speakers: exit 1 when the acceptance targets are missed");
  if (const int rc = tachi::common::parse(app, argc, argv); rc >= 0) return rc;
  if (!speakers.empty()) {
    VoiceConfig c = load_voice_config(config_file);
    if (!start_phrase.empty()) set_phrase(c, VoiceCommand::Start, start_phrase);
    if (!stop_phrase.empty()) set_phrase(c, VoiceCommand::Stop, stop_phrase);
    if (verify) c.verify_min_log_ratio = *verify;
    if (margin) c.verify_min_margin = *margin;
    if (phone_loop) c.phone_loop_probability = *phone_loop;
    std::optional<std::pair<double, double>> sweep_range;
    if (sweep_ratio.size() == 2) sweep_range = std::pair{sweep_ratio[0], sweep_ratio[1]};
    return speakers_main(c, speakers, seed_offset, threads, no_command_s, cache, sweep_range, check, only_conditions, only_contexts, only_variants, only_voices, dump,
                         first_word_sweep);
  }
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
