#include "tachi/sensor/voice_spotter.hpp"

#include "tachi/sensor/voice_audio.hpp"

#include <pocketsphinx.h>
#include <cmn.h>
#include <fe.h>
#include <feat.h>
#include <fsg_model.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <tuple>
#include <unistd.h>

namespace tachi::sensor {

struct KeywordSpotter::Impl {
  VoiceConfig config;
  // One lane per warp factor (VoiceConfig::warps): a keyword search and the second pass's decoders, all
  // with the same front end (its mel filters are built once, when a decoder is made, so each warp needs
  // decoders of its own). Every lane hears all the audio; their hits are judged together (verify()).
  struct Lane {
    double warp = 1.0;
    cmd_ln_t* cmdln = nullptr;
    ps_decoder_t* decoder = nullptr;  // the keyword search
    long utterance_start = 0;          // sample at which its current utterance began
    long frames_before_utterance = 0;  // frames it read in earlier utterances
    long last_hit_end = -1L << 30;     // sample at which its last reported hit ended (none yet)
    // The second pass has its own decoder: switching the keyword decoder to other searches and back
    // shifted the frames of its later hits by the frames the other searches had read.
    cmd_ln_t* verifier_cmdln = nullptr;
    ps_decoder_t* verifier = nullptr;
    // The garbage-model grammars have a decoder of their own with beams wide enough that a phrase the
    // audio does not hold still reaches the grammar's end (with the default beams the free phone loop
    // outscores it in every frame and the path is pruned: no score at all).
    cmd_ln_t* garbage_cmdln = nullptr;
    ps_decoder_t* garbage_verifier = nullptr;
  };
  std::vector<Lane> lanes;
  long samples = 0;
  std::vector<std::int16_t> audio;  // the latest audio, from sample audio_start on
  long audio_start = 0;

  std::size_t phrase_index(const std::string& phrase) const {
    return static_cast<std::size_t>(std::find_if(config.phrases.begin(), config.phrases.end(),
                                                 [&](const VoicePhrase& p) { return p.phrase == phrase; }) -
                                    config.phrases.begin());
  }
  struct PendingHit {
    std::size_t phrase;  // index into config.phrases
    long begin, end;     // samples from stream start
    std::size_t lane;    // the lane whose keyword search hit
  };
  std::vector<PendingHit> pending;  // keyword hits waiting for the audio the second pass needs
  /// Runs the second pass over the pending hits that ended by sample `ended_by`; appends the accepted
  /// (with report_refused, every judged utterance's verdict, accepted or not).
  void verify_pending(long ended_by, std::vector<VoiceDetection>& accepted);
  bool report_refused = false;
  /// The lane of warp 1.0 (lanes.size() when config.warps has none: the warped lanes' judgement alone).
  std::size_t unwarped = 0;
  long group_end = -1L << 30;      // where the last judged utterance's hits ended
  long unwarped_end = -1L << 30;   // ... the last one that held a hit of the unwarped lane
  long command_end = -1L << 30;    // ... the last one that gave a command

  /// The second pass over the audio of one hit: which phrase it was, and its log-likelihood ratio
  /// against a free phone loop per frame (-infinity when no phrase fits the audio).
  struct Verdict {
    std::optional<VoicePhrase> phrase;
    double log_ratio = -std::numeric_limits<double>::infinity();
    /// log_ratio minus the best log ratio of a phrase of another command (+infinity when none fits).
    double margin = std::numeric_limits<double>::infinity();
    /// The ratio over the phrase's own frames (the words around it left out: a phrase inside a
    /// sentence), and its margin over another command.
    double phrase_log_ratio = -std::numeric_limits<double>::infinity();
    double phrase_margin = std::numeric_limits<double>::infinity();
    /// The phrase's level above the background's floor, dB (level_above_floor_db).
    double level_db = std::numeric_limits<double>::quiet_NaN();
    /// The ratio with a phone loop before and after the phrase (the words around it explained), and
    /// the phrase's margin so scored over the best phrase of another command (negative: the garbage
    /// grammar prefers the other command).
    double garbage_log_ratio = -std::numeric_limits<double>::infinity();
    double garbage_margin = std::numeric_limits<double>::infinity();
    /// The phrase's frames as the phrase grammar and the garbage grammar align it (10 ms each; 0: none).
    int phrase_frames = 0;
    int garbage_frames = 0;
    /// The phrase the unwarped lane scores best on the same window (with the warped lanes' judgement).
    std::optional<VoicePhrase> unwarped_best;
    /// The window's first sample, and the reported phrase and its best rival as the garbage grammar
    /// aligns them (VoiceDetection::Alignment; frames from the window's start).
    long from = 0;
    struct Words {
      int first = -1, first_word_last = -1, last = -1;
      double first_word_ratio = std::numeric_limits<double>::quiet_NaN(), rest_ratio = std::numeric_limits<double>::quiet_NaN();
      double garbage_ratio = std::numeric_limits<double>::quiet_NaN();
    };
    Words aligned, rival;
  };
  /// The second pass over samples [begin - before, end + 0.6 s) by the lanes `use` (indices into
  /// lanes), each phrase scored at the best of their warps.
  Verdict verify(long begin, long end, const std::vector<std::size_t>& use, long before);
  /// One lane's second pass over one window: per phrase, as Verdict's fields (kept while one utterance
  /// is judged, so that the warped lanes' judgement reuses the unwarped lane's decodings).
  struct LaneScores {
    double loop_score = 0.0;
    std::vector<double> log_ratio, phrase_only, garbage_ratio;
    std::vector<std::pair<int, int>> span;  // the phrase's first and last frame in the window
    std::vector<int> phrase_frames, garbage_frames;
    std::vector<Verdict::Words> garbage_words;  // each phrase's words as the garbage grammar aligns them
    std::vector<std::tuple<int, int, double>> loop_segments;  // the phone loop's path: first, last frame (window's), score
    bool garbage_scored = false;
  };
  std::map<std::tuple<std::size_t, long, long>, LaneScores> window_scores;  // by lane, window start, end
  LaneScores& lane_scores(std::size_t lane, long from, long to, bool garbage);
  /// Makes the keyword search (and, with the second pass, its decoders) at one warp factor.
  void add_lane(double warp);
  /// Runs one lane's keyword search over new samples; queues its hits (or, in one pass, reports them).
  void search(Lane& lane, std::span<const std::int16_t> block, std::vector<VoiceDetection>& found);

  ~Impl() {
    for (auto& lane : lanes) {
      if (lane.decoder != nullptr) {
        ps_end_utt(lane.decoder);
        ps_free(lane.decoder);
      }
      if (lane.cmdln != nullptr) cmd_ln_free_r(lane.cmdln);
      if (lane.verifier != nullptr) ps_free(lane.verifier);
      if (lane.verifier_cmdln != nullptr) cmd_ln_free_r(lane.verifier_cmdln);
      if (lane.garbage_verifier != nullptr) ps_free(lane.garbage_verifier);
      if (lane.garbage_cmdln != nullptr) cmd_ln_free_r(lane.garbage_cmdln);
    }
  }
};

namespace {
constexpr long kSamplesPerFrame = kVoiceSampleRate / 100;     // pocketsphinx's 10 ms frames
constexpr std::size_t kKeepSamples = 4 * kVoiceSampleRate;   // replayable audio: longer than a phrase
constexpr long kRedetectSamples = kVoiceSampleRate / 2;      // a hit ending < 0.5 s after the last one is it again

/// The phone loop's score over frames [first, last] of a window, each of its path's segments (first frame,
/// last frame, acoustic score) pro-rated by the frames it shares with them.
double loop_score_over(const std::vector<std::tuple<int, int, double>>& segments, int first, int last) {
  double sum = 0.0;
  for (const auto& [f0, f1, acoustic] : segments) {
    const int a = std::max(first, f0), b = std::min(last, f1);
    if (b >= a) sum += acoustic * (b - a + 1) / (f1 - f0 + 1);
  }
  return sum;
}
// The audio the second pass sees around a keyword hit. The keyword search reports a phrase as soon as
// its last state scores well enough, up to 0.5 s before the phrase ends (flite "stop cutting": hit at
// 3.98 s, the word's end at 4.49 s); a grammar cannot be aligned to a phrase cut short.
constexpr long kVerifyBeforeSamples = 3 * kVoiceSampleRate / 10;
constexpr long kVerifyAfterSamples = 6 * kVoiceSampleRate / 10;
constexpr long kVerifyWideBeforeSamples = 8 * kVoiceSampleRate / 10;
constexpr const char* kKeywordSearch = "commands";
const std::string kPhoneLoopSearch = "verify-phone-loop";
std::string grammar_search(std::size_t phrase) { return "verify-phrase-" + std::to_string(phrase); }
std::string garbage_search(std::size_t phrase) { return "verify-garbage-" + std::to_string(phrase); }
// The garbage model around a phrase: one dictionary word per context-independent phone of the en-us
// model (CMU's 39 phones), in a free loop before and after the phrase.
constexpr std::array<const char*, 39> kGarbagePhones{"AA", "AE", "AH", "AO", "AW", "AY", "B",  "CH", "D",  "DH", "EH", "ER", "EY",
                                                     "F",  "G",  "HH", "IH", "IY", "JH", "K",  "L",  "M",  "N",  "NG", "OW", "OY",
                                                     "P",  "R",  "S",  "SH", "T",  "TH", "UH", "UW", "V",  "W",  "Y",  "Z",  "ZH"};
constexpr const char* kGarbagePrefix = "tachi_garbage_";
/// One word (or filler, or phone) of a decoder's best path.
struct PathSegment {
  std::string word;
  int first_frame = 0, last_frame = 0;
  double acoustic = 0.0;  // log-likelihood, pocketsphinx's log base and scaling
};
std::vector<PathSegment> best_path(ps_decoder_t* decoder) {
  std::vector<PathSegment> path;
  for (ps_seg_t* seg = ps_seg_iter(decoder); seg != nullptr; seg = ps_seg_next(seg)) {
    PathSegment s{ps_seg_word(seg)};
    int ascr = 0, lscr = 0, lback = 0;
    ps_seg_prob(seg, &ascr, &lscr, &lback);
    s.acoustic = ascr;
    ps_seg_frames(seg, &s.first_frame, &s.last_frame);
    path.push_back(std::move(s));
  }
  return path;
}
/// Silence and noise words: "<sil>", "<s>", "</s>", "[NOISE]", "[SPEECH]".
bool is_filler(const std::string& word) { return word.empty() || word.front() == '<' || word.front() == '['; }

/// How far the phrase's audio [p0, p1) (samples from stream start) stands above the background: its
/// mean power over the 20th percentile of the 10 ms frame powers of the rest of the kept audio, in dB.
/// A low quantile of frame energies estimates the noise floor even while speech fills much of the
/// audio (quantile-based noise estimation: Stahl, Fischer & Bippus, ICASSP 2000).
double level_above_floor_db(const std::vector<std::int16_t>& audio, long audio_start, long p0, long p1) {
  constexpr long kFrame = kVoiceSampleRate / 100;
  std::vector<double> background;
  double phrase_power = 0.0;
  long phrase_samples = 0;
  for (long at = audio_start; at + kFrame <= audio_start + static_cast<long>(audio.size()); at += kFrame) {
    double power = 0.0;
    for (long i = at; i < at + kFrame; ++i) {
      const double v = audio[static_cast<std::size_t>(i - audio_start)];
      power += v * v;
    }
    if (at + kFrame > p0 && at < p1) {
      phrase_power += power;
      phrase_samples += kFrame;
    } else {
      background.push_back(power / kFrame);
    }
  }
  if (phrase_samples == 0 || background.empty()) return std::numeric_limits<double>::quiet_NaN();
  const auto q = background.begin() + static_cast<std::ptrdiff_t>(background.size() / 5);
  std::nth_element(background.begin(), q, background.end());
  return 10.0 * std::log10((phrase_power / static_cast<double>(phrase_samples) + 1.0) / (*q + 1.0));
}

/// The second pass's margins over the other commands, verification_accepts()'s first tests: too close
/// to another command is a miss, never a wrong command (NaN margins compare false: not met). The garbage
/// margin is the same margin with the words around the phrase explained by the garbage model: a phrase
/// that wins only because it stretched over a neighbouring word loses there.
/// The first words' margin (VoiceConfig::verify_min_first_word_margin): the reported phrase's first word,
/// as the garbage grammar aligns it, against the first word of the best phrase of another command (the
/// rival), each a ratio against the phone loop per frame. The commands share "cutting": where the first
/// word is blurred, the whole phrase's margins rest on the words around it, and the first words decide.
/// Not checked when either first word is not aligned (NaN: no rival, nothing to confuse it with).
bool first_word_margin_met(const VoiceConfig& config, const VoiceDetection& d) {
  if (!config.verify_min_first_word_margin) return true;
  const double margin = d.aligned.first_word_ratio - d.rival.first_word_ratio;
  return std::isnan(margin) || margin >= *config.verify_min_first_word_margin;
}

bool margins_met(const VoiceConfig& config, const VoiceDetection& d) {
  return d.command_margin >= config.verify_min_margin &&
         (config.verify_min_phrase_margin <= 0.0 || d.phrase_margin >= config.verify_min_phrase_margin) &&
         (!config.verify_min_garbage_margin || d.garbage_margin >= *config.verify_min_garbage_margin) &&
         first_word_margin_met(config, d);
}

/// sphinxbase keeps the warp factor of its front ends in static variables, read while a decoder is made
/// (the mel filters are built then): decoders are made one at a time, and each names its warp
/// (a decoder made without one would leave the next one with the same warp unwarped).
std::mutex decoder_setup;

/// "1.13" for -warp_params.
std::string warp_text(double warp) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", warp);
  return text;
}

// pocketsphinx reads keyword lists from a file only.
std::string write_kws_file(const std::string& text) {
  std::string path = (std::filesystem::temp_directory_path() / "tachi-voice-XXXXXX").string();
  const int fd = ::mkstemp(path.data());
  if (fd < 0) throw std::runtime_error("cannot create a temporary keyword list in " + std::filesystem::temp_directory_path().string());
  const auto written = ::write(fd, text.data(), text.size());
  ::close(fd);
  if (written != static_cast<ssize_t>(text.size())) throw std::runtime_error("cannot write the temporary keyword list " + path);
  return path;
}
}  // namespace

KeywordSpotter::Impl::LaneScores& KeywordSpotter::Impl::lane_scores(std::size_t l, long from, long to, bool garbage) {
  const auto key = std::make_tuple(l, from, to);
  auto found = window_scores.find(key);
  const bool fresh = found == window_scores.end();
  if (fresh) found = window_scores.emplace(key, LaneScores{}).first;
  LaneScores& s = found->second;
  if (!fresh && (s.garbage_scored || !garbage)) return s;
  Lane& lane = lanes[l];
  // Both decodings normalise the cepstra with the live mean of the keyword search at the same warp: a
  // short window alone would start from the model's initial estimate.
  std::vector<mfcc_t> cepstral_mean;
  {
    cmn_t* cmn = ps_get_feat(lane.decoder)->cmn_struct;
    cepstral_mean.assign(static_cast<std::size_t>(cmn->veclen), 0);
    cmn_live_get(cmn, cepstral_mean.data());
  }
  const auto decode = [&](const char* search, ps_decoder_t* ps) {
    if (ps_set_search(ps, search) < 0) throw std::runtime_error(std::string("pocketsphinx has no search ") + search);
    cmn_live_set(ps_get_feat(ps)->cmn_struct, cepstral_mean.data());
    ps_start_utt(ps);
    if (ps_process_raw(ps, audio.data() + (from - audio_start), static_cast<std::size_t>(to - from), FALSE, FALSE) < 0)
      throw std::runtime_error("pocketsphinx failed to process audio");
    ps_end_utt(ps);
    return best_path(ps);
  };
  const std::size_t n = config.phrases.size();
  constexpr double kNone = -std::numeric_limits<double>::infinity();
  if (fresh) {
    s.log_ratio.assign(n, kNone);
    s.phrase_only.assign(n, kNone);
    s.garbage_ratio.assign(n, kNone);
    s.span.assign(n, {-1, -1});
    s.phrase_frames.assign(n, 0);
    s.garbage_frames.assign(n, 0);
    const auto loop_path = decode(kPhoneLoopSearch.c_str(), lane.verifier);
    // The decoder numbers frames on from earlier utterances: frames relative to the window's start.
    const int loop_base = loop_path.empty() ? 0 : loop_path.front().first_frame;
    for (const auto& seg : loop_path) s.loop_score += seg.acoustic;
    for (const auto& seg : loop_path) s.loop_segments.emplace_back(seg.first_frame - loop_base, seg.last_frame - loop_base, seg.acoustic);
    const auto loop_over = [&](int first, int last) { return loop_score_over(s.loop_segments, first, last); };
    for (std::size_t i = 0; i < n; ++i) {
      double phrase_score = 0.0, words_score = 0.0;
      int phrase_frames = 0;
      std::pair<int, int> span{-1, -1};
      const auto path = decode(grammar_search(i).c_str(), lane.verifier);
      const int base = path.empty() ? 0 : path.front().first_frame;
      for (const auto& seg : path) {
        phrase_score += seg.acoustic;
        if (is_filler(seg.word)) continue;
        phrase_frames += seg.last_frame - seg.first_frame + 1;
        words_score += seg.acoustic;
        if (span.first < 0) span.first = seg.first_frame - base;
        span.second = seg.last_frame - base;
      }
      if (phrase_frames == 0) continue;  // the phrase cannot be aligned to this audio
      s.log_ratio[i] = (phrase_score - s.loop_score) / phrase_frames;
      s.phrase_frames[i] = phrase_frames;
      s.span[i] = span;
      // The phrase said inside other words: the ratio over the phrase's own frames only, the phone
      // loop's score pro-rated over the same frames, so that the words around it count for neither.
      s.phrase_only[i] = (words_score - loop_over(span.first, span.second)) / phrase_frames;
    }
  }
  if (garbage && !s.garbage_scored) {
    s.garbage_words.assign(n, Verdict::Words{});
    const auto loop_over = [&](int first, int last) { return loop_score_over(s.loop_segments, first, last); };
    // The same phrases with a garbage model (a free phone loop) before and after them instead of the
    // silence and noise fillers alone: the filler-model keyword verification of Rose & Paul (ICASSP
    // 1990), where the fillers explain the non-keyword speech. With silence fillers only, the words
    // around a phrase must be explained by the phrase itself: in "that is enough, stop cutting" the
    // grammar of "begin cutting" stretches "begin" over "enough" ("-nough" ends like "-gin") and beats
    // "stop cutting", whose grammar leaves "that is enough" to the silence model. With the phone loop
    // around both, each phrase is aligned where it fits best and the commands compete on the phrase.
    // Score: the ratio of the whole window against the free phone loop, per frame of the phrase, as above.
    for (std::size_t i = 0; i < n; ++i) {
      double score = 0.0;
      int frames = 0;
      const auto gpath = decode(garbage_search(i).c_str(), lane.garbage_verifier);
      const int gbase = gpath.empty() ? 0 : gpath.front().first_frame;
      Verdict::Words& w = s.garbage_words[i];
      double first_word = 0.0, rest = 0.0;
      for (const auto& seg : gpath) {
        score += seg.acoustic;
        if (!is_filler(seg.word) && seg.word.rfind(kGarbagePrefix, 0) != 0) {
          frames += seg.last_frame - seg.first_frame + 1;
          if (w.first < 0) {
            w.first = seg.first_frame - gbase;
            w.first_word_last = seg.last_frame - gbase;
            first_word = seg.acoustic;
          } else {
            rest += seg.acoustic;
          }
          w.last = seg.last_frame - gbase;
        }
      }
      if (frames == 0) continue;
      s.garbage_ratio[i] = (score - s.loop_score) / frames;
      s.garbage_frames[i] = frames;
      w.garbage_ratio = s.garbage_ratio[i];
      w.first_word_ratio = (first_word - loop_over(w.first, w.first_word_last)) / (w.first_word_last - w.first + 1);
      if (w.last > w.first_word_last)
        w.rest_ratio = (rest - loop_over(w.first_word_last + 1, w.last)) / (w.last - w.first_word_last);
    }
    s.garbage_scored = true;
  }
  return s;
}

// Keyword verification by a likelihood-ratio test against a background model (Rose & Paul, "A hidden
// Markov model based keyword recognition system", ICASSP 1990; as utterance verification, Sukkar &
// Lee, IEEE Trans. Speech Audio Proc. 4(6), 1996). The audio around the hit, X (0.3 s before it to
// 0.6 s after it), is decoded again, once with a grammar that allows only the phrase, with silence and
// noise fillers around it, and once with a free loop of context-independent phones, the background
// model. The score is the log-likelihood ratio per frame of the phrase,
//   LLR = (log p(X | fillers + phrase) - log p(X | phone loop)) / T_phrase,
// from the acoustic scores of the two best paths over the same frames; dividing by the phrase's
// T_phrase frames is Sukkar & Lee's duration normalisation, so that one threshold serves all phrases.
// The window holds the audio around the phrase too, where the grammar has only silence and noise:
// a phrase inside ongoing speech scores low. That is what rejects the keyword search's false alarms in
// ordinary reading, and it asks a command to be said on its own ("of clubs" inside "four of clubs
// seven" scores -64, the same phrase alone -4 to -13; docs/voice.md).
KeywordSpotter::Impl::Verdict KeywordSpotter::Impl::verify(long begin, long end, const std::vector<std::size_t>& use, long before) {
  Verdict verdict;
  const long from = std::max(begin - before, audio_start);
  const long to = std::min(end + kVerifyAfterSamples, audio_start + static_cast<long>(audio.size()));
  if (to <= from || use.empty()) return verdict;
  // Each phrase's scores, the best over the lanes' warps (VoiceConfig::warps): a phrase is scored at the
  // warp where the voice's formants fit the model best (Lee & Rose 1998 choose the warp of the highest
  // likelihood; here the ratio against the phone loop at the same warp, so that the warps compare).
  // The commands then compete on their best scores, so another command's better fit at any warp
  // counts against the margin: a command two warps disagree on is dropped, not guessed.
  const std::size_t n = config.phrases.size();
  constexpr double kNone = -std::numeric_limits<double>::infinity();
  std::vector<double> log_ratio(n, kNone), phrase_only(n, kNone), garbage_ratio(n, kNone);
  std::vector<std::pair<int, int>> phrase_span(n, {-1, -1});
  std::vector<int> phrase_frame_count(n, 0), garbage_frame_count(n, 0);
  std::vector<Verdict::Words> garbage_words(n);
  verdict.from = from;
  for (const std::size_t l : use) {
    const LaneScores& s = lane_scores(l, from, to, false);
    for (std::size_t i = 0; i < n; ++i) {
      if (!(s.log_ratio[i] > log_ratio[i])) continue;
      log_ratio[i] = s.log_ratio[i];
      phrase_frame_count[i] = s.phrase_frames[i];
      phrase_span[i] = s.span[i];
      phrase_only[i] = s.phrase_only[i];
    }
  }
  // A phrase that cannot be aligned may be longer than the one the search hit and begin before the
  // window ("stop cutting" hit on flite rms's "begin cutting": "be" lay before it): judged again over
  // a window reaching further back, so that every phrase is scored on the whole utterance.
  if (before == kVerifyBeforeSamples && std::any_of(log_ratio.begin(), log_ratio.end(), [](double r) { return !std::isfinite(r); }))
    return verify(begin, end, use, kVerifyWideBeforeSamples);
  const auto best = static_cast<std::size_t>(std::max_element(log_ratio.begin(), log_ratio.end()) - log_ratio.begin());
  if (!std::isfinite(log_ratio[best])) return verdict;
  // The garbage model's scores (lane_scores()), the best over the warps, as above.
  for (const std::size_t l : use) {
    const LaneScores& s = lane_scores(l, from, to, true);
    for (std::size_t i = 0; i < n; ++i) {
      if (s.garbage_frames[i] == 0) continue;
      if (!(s.garbage_ratio[i] > garbage_ratio[i]) && garbage_frame_count[i] > 0) continue;
      garbage_ratio[i] = s.garbage_ratio[i];
      garbage_frame_count[i] = s.garbage_frames[i];
      garbage_words[i] = s.garbage_words[i];
    }
  }
  verdict.aligned = garbage_words[best];
  {
    double rival_ratio = -std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < n; ++i)
      if (config.phrases[i].command != config.phrases[best].command && garbage_ratio[i] > rival_ratio) {
        rival_ratio = garbage_ratio[i];
        verdict.rival = garbage_words[i];
      }
  }
  verdict.phrase = config.phrases[best];
  verdict.log_ratio = log_ratio[best];
  verdict.phrase_frames = phrase_frame_count[best];
  verdict.garbage_frames = garbage_frame_count[best];
  for (std::size_t i = 0; i < config.phrases.size(); ++i)
    if (config.phrases[i].command != config.phrases[best].command && std::isfinite(log_ratio[i]))
      verdict.margin = std::min(verdict.margin, log_ratio[best] - log_ratio[i]);
  verdict.phrase_log_ratio = phrase_only[best];
  for (std::size_t i = 0; i < config.phrases.size(); ++i)
    if (config.phrases[i].command != config.phrases[best].command && std::isfinite(phrase_only[i]))
      verdict.phrase_margin = std::min(verdict.phrase_margin, phrase_only[best] - phrase_only[i]);
  verdict.garbage_log_ratio = garbage_ratio[best];
  for (std::size_t i = 0; i < config.phrases.size(); ++i)
    if (config.phrases[i].command != config.phrases[best].command && std::isfinite(garbage_ratio[i]))
      verdict.garbage_margin = std::min(verdict.garbage_margin, garbage_ratio[best] - garbage_ratio[i]);
  if (phrase_span[best].first >= 0) {
    const long p0 = from + phrase_span[best].first * kSamplesPerFrame, p1 = from + (phrase_span[best].second + 1) * kSamplesPerFrame;
    verdict.level_db = level_above_floor_db(audio, audio_start, p0, p1);
  }
  if (unwarped < lanes.size()) {
    const auto& u = lane_scores(unwarped, from, to, false).log_ratio;
    const auto ub = static_cast<std::size_t>(std::max_element(u.begin(), u.end()) - u.begin());
    if (std::isfinite(u[ub])) verdict.unwarped_best = config.phrases[ub];
  }
  return verdict;
}

// One pair of second-pass decoders at one warp factor (made under decoder_setup, as every decoder).
void KeywordSpotter::Impl::add_lane(double warp) {
  Lane& lane = lanes.emplace_back();  // freed by ~Impl whatever is made of it
  lane.warp = warp;
  const std::string warp_params = warp_text(warp);
  char phone_loop[32];
  std::snprintf(phone_loop, sizeof phone_loop, "%g", config.phone_loop_probability);
  lane.cmdln = cmd_ln_init(nullptr, ps_args(), TRUE, "-hmm", config.model_dir.c_str(), "-dict", config.dictionary.c_str(), "-kws_plp",
                           phone_loop,
                           // Every frame is searched: with pocketsphinx's voice-activity gate dropping
                           // silent frames, a hit's frame numbers cannot be mapped back to stream time
                           // (after the first restart they pointed past the audio: the replay and
                           // the second pass lost the hits that followed).
                           "-remove_silence", "no", "-warp_type", "inverse_linear", "-warp_params", warp_params.c_str(), "-logfn",
                           "/dev/null", nullptr);
  if (lane.cmdln == nullptr) throw std::runtime_error("pocketsphinx rejected its arguments");
  lane.decoder = ps_init(lane.cmdln);
  if (lane.decoder == nullptr) throw std::runtime_error("pocketsphinx could not load " + config.model_dir);
  for (const auto& p : config.phrases) {
    std::istringstream words(p.phrase);
    std::string word;
    while (words >> word)
      if (ps_lookup_word(lane.decoder, word.c_str()) == nullptr)
        throw std::runtime_error("word \"" + word + "\" of phrase \"" + p.phrase + "\" is not in " + config.dictionary);
  }
  const std::string kws = write_kws_file(kws_file_text(config.phrases));
  const int rc = ps_set_kws(lane.decoder, kKeywordSearch, kws.c_str());
  std::filesystem::remove(kws);
  if (rc < 0) throw std::runtime_error("pocketsphinx rejected the keyword list");
  if (ps_set_search(lane.decoder, kKeywordSearch) < 0) throw std::runtime_error("pocketsphinx rejected the keyword list");
  if (ps_start_utt(lane.decoder) < 0) throw std::runtime_error("pocketsphinx could not start decoding");
  if (!config.verify_min_log_ratio) return;
  lane.verifier_cmdln = cmd_ln_init(nullptr, ps_args(), TRUE, "-hmm", config.model_dir.c_str(), "-dict", config.dictionary.c_str(),
                                      "-remove_silence", "no", "-allphone_ci", "yes", "-warp_type", "inverse_linear", "-warp_params",
                                      warp_params.c_str(), "-logfn", "/dev/null", nullptr);
  if (lane.verifier_cmdln != nullptr) lane.verifier = ps_init(lane.verifier_cmdln);
  if (lane.verifier == nullptr) throw std::runtime_error("pocketsphinx could not load " + config.model_dir + " for the second pass");
  for (std::size_t i = 0; i < config.phrases.size(); ++i) {
    // One grammar per phrase, each of its own name (pocketsphinx keeps grammars by name).
    const std::string grammar = "#JSGF V1.0;\ngrammar phrase" + std::to_string(i) + ";\npublic <phrase> = " + config.phrases[i].phrase + ";\n";
    if (ps_set_jsgf_string(lane.verifier, grammar_search(i).c_str(), grammar.c_str()) < 0)
      throw std::runtime_error("pocketsphinx rejected the grammar " + grammar);
  }
  // The garbage words, then per phrase a finite-state grammar: a free loop of them, the phrase's
  // words, a free loop again. Built as an FSG rather than JSGF because JSGF gives each of the 39
  // alternatives probability 1/39, and with the language weight that penalty per phone made the
  // decoder stretch the phrase over the words around it (or lose the path in the beam) instead of
  // using the loop. A garbage phone here costs no grammar probability, as a phone costs nothing in
  // the allphone background loop it is compared with.
  lane.garbage_cmdln = cmd_ln_init(nullptr, ps_args(), TRUE, "-hmm", config.model_dir.c_str(), "-dict", config.dictionary.c_str(),
                                     "-remove_silence", "no", "-beam", "1e-300", "-pbeam", "1e-300", "-wbeam", "1e-300", "-warp_type",
                                     "inverse_linear", "-warp_params", warp_params.c_str(), "-logfn", "/dev/null", nullptr);
  if (lane.garbage_cmdln != nullptr) lane.garbage_verifier = ps_init(lane.garbage_cmdln);
  if (lane.garbage_verifier == nullptr) throw std::runtime_error("pocketsphinx could not load " + config.model_dir + " for the garbage model");
  std::vector<std::string> garbage_words;
  for (const char* phone : kGarbagePhones) {
    std::string word = kGarbagePrefix + std::string(phone);
    std::transform(word.begin(), word.end(), word.begin(), [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
    if (ps_add_word(lane.garbage_verifier, word.c_str(), phone, FALSE) < 0)
      throw std::runtime_error(std::string("the acoustic model has no phone ") + phone + " for the garbage model");
    garbage_words.push_back(std::move(word));
  }
  const auto lw = static_cast<float>(cmd_ln_float32_r(lane.garbage_cmdln, "-lw"));
  for (std::size_t i = 0; i < config.phrases.size(); ++i) {
    std::vector<std::string> words;
    std::istringstream in(config.phrases[i].phrase);
    for (std::string w; in >> w;) words.push_back(w);
    const auto n = static_cast<int>(words.size());
    fsg_model_t* fsg = fsg_model_init(garbage_search(i).c_str(), ps_get_logmath(lane.garbage_verifier), lw, n + 1);
    fsg->start_state = 0;
    fsg->final_state = n;
    for (int k = 0; k < n; ++k) fsg_model_trans_add(fsg, k, k + 1, 0, fsg_model_word_add(fsg, words[static_cast<std::size_t>(k)].c_str()));
    for (const auto& g : garbage_words) {
      const int wid = fsg_model_word_add(fsg, g.c_str());
      fsg_model_trans_add(fsg, 0, 0, 0, wid);
      fsg_model_trans_add(fsg, n, n, 0, wid);
    }
    const int set = ps_set_fsg(lane.garbage_verifier, garbage_search(i).c_str(), fsg);
    fsg_model_free(fsg);  // the search keeps its own reference
    if (set < 0) throw std::runtime_error("pocketsphinx rejected the garbage grammar of \"" + config.phrases[i].phrase + "\"");
  }
  if (ps_set_allphone(lane.verifier, kPhoneLoopSearch.c_str(), nullptr) < 0) throw std::runtime_error("pocketsphinx could not set up a phone loop");
}

KeywordSpotter::KeywordSpotter(const VoiceConfig& config, bool report_refused) : impl_(std::make_unique<Impl>()) {
  if (const auto why = validate(config)) throw std::runtime_error("voice config: " + *why);
  namespace fs = std::filesystem;
  if (!fs::is_directory(config.model_dir))
    throw std::runtime_error("acoustic model " + config.model_dir + " not found (install pocketsphinx-en-us)");
  if (!fs::is_regular_file(config.dictionary))
    throw std::runtime_error("pronunciation dictionary " + config.dictionary + " not found (install pocketsphinx-en-us)");
  impl_->config = config;
  impl_->report_refused = report_refused;
  const std::lock_guard setup{decoder_setup};
  // One pass reports each keyword hit at once, with nothing to judge the hits of several lanes on one
  // utterance together: it searches unwarped.
  if (config.verify_min_log_ratio)
    for (const double warp : config.warps) impl_->add_lane(warp);
  else
    impl_->add_lane(1.0);
  const auto& lanes = impl_->lanes;
  impl_->unwarped = static_cast<std::size_t>(std::find_if(lanes.begin(), lanes.end(), [](const Impl::Lane& l) { return l.warp == 1.0; }) - lanes.begin());
}

KeywordSpotter::~KeywordSpotter() = default;

double KeywordSpotter::time_s() const noexcept { return static_cast<double>(impl_->samples) / static_cast<double>(kVoiceSampleRate); }

std::vector<VoiceDetection> KeywordSpotter::process(std::span<const std::int16_t> samples) {
  std::vector<VoiceDetection> found;
  if (samples.empty()) return found;
  impl_->samples += static_cast<long>(samples.size());
  // The utterance's audio (the last kKeepSamples of it), for the replay and the second pass below.
  impl_->audio.insert(impl_->audio.end(), samples.begin(), samples.end());
  if (impl_->audio.size() > kKeepSamples) {
    const std::size_t drop = impl_->audio.size() - kKeepSamples;
    impl_->audio.erase(impl_->audio.begin(), impl_->audio.begin() + static_cast<std::ptrdiff_t>(drop));
    impl_->audio_start += static_cast<long>(drop);
  }
  for (auto& lane : impl_->lanes) impl_->search(lane, samples, found);
  // The lanes' hits in the order of the audio, so that hits of several lanes on one utterance meet.
  std::stable_sort(impl_->pending.begin(), impl_->pending.end(), [](const auto& a, const auto& b) { return a.begin < b.begin; });
  impl_->verify_pending(impl_->samples - kVerifyAfterSamples, found);
  return found;
}

void KeywordSpotter::Impl::search(Lane& lane, std::span<const std::int16_t> block, std::vector<VoiceDetection>& found) {
  if (ps_process_raw(lane.decoder, block.data(), block.size(), FALSE, FALSE) < 0) throw std::runtime_error("pocketsphinx failed to process audio");
  for (int round = 0; round < 4; ++round) {  // a replay may hold another hit; a few at most
    const char* hyp = ps_get_hyp(lane.decoder, nullptr);
    if (hyp == nullptr || hyp[0] == '\0') break;
    // Restart, or the same hit is reported with every later block; then replay the audio after the
    // hit's end, which the decoder held and a restart alone drops: in "go forward ten meters" the
    // second phrase follows the first at once and was never found that way.
    struct Hit {
      std::string words;
      long begin, end;  // samples from stream start
    };
    std::vector<Hit> hits;
    long last_end = lane.utterance_start;  // no segment: resume where the utterance began, as before
    for (ps_seg_t* seg = ps_seg_iter(lane.decoder); seg != nullptr; seg = ps_seg_next(seg)) {
      int start_frame = 0, end_frame = 0;
      ps_seg_frames(seg, &start_frame, &end_frame);
      // The keyword search numbers frames from the decoder's first utterance on, not from this one's start.
      hits.push_back({ps_seg_word(seg), lane.utterance_start + (start_frame - lane.frames_before_utterance) * kSamplesPerFrame,
                      lane.utterance_start + (end_frame + 1 - lane.frames_before_utterance) * kSamplesPerFrame});
      last_end = std::max(last_end, hits.back().end);
    }
    ps_end_utt(lane.decoder);
    lane.frames_before_utterance += ps_get_n_frames(lane.decoder);
    // The replay can hold the tail of the phrase just reported ("... cutting"), found again ending
    // just after it; a real next phrase ends at least a phrase's length later. Rejected hits count
    // too, so that the second pass's threshold can be swept over one run's scores.
    if (last_end - lane.last_hit_end >= kRedetectSamples) {
      for (const auto& h : hits)
        for (const auto& p : phrases_in_hypothesis(h.words, config.phrases)) {
          if (config.verify_min_log_ratio)
            pending.push_back({phrase_index(p.phrase), h.begin, h.end, static_cast<std::size_t>(&lane - lanes.data())});
          else
            found.push_back({static_cast<double>(samples) / kVoiceSampleRate, p.command, p.phrase});
        }
      lane.last_hit_end = last_end;
    }
    ps_start_utt(lane.decoder);
    const long resume = std::max(last_end, audio_start);
    lane.utterance_start = resume;
    const long from = resume - audio_start;
    if (from >= static_cast<long>(audio.size())) break;
    if (ps_process_raw(lane.decoder, audio.data() + from, audio.size() - static_cast<std::size_t>(from), FALSE, FALSE) < 0)
      throw std::runtime_error("pocketsphinx failed to process audio");
  }
}

std::vector<VoiceDetection> KeywordSpotter::finish() {
  std::vector<VoiceDetection> found;
  impl_->verify_pending(impl_->samples, found);
  return found;
}

void KeywordSpotter::Impl::verify_pending(long ended_by, std::vector<VoiceDetection>& accepted) {
  // Each hit waits for the audio just after it: the keyword search may report a phrase before its
  // last phone has ended, and the second pass must see all of it.
  while (!pending.empty() && pending.front().end <= ended_by) {
    const PendingHit hit = pending.front();
    pending.erase(pending.begin());
    // Another lane's hit on an utterance already judged, ending within 0.5 s of it (as kRedetectSamples
    // within a lane): the same utterance, judged once. The unwarped lane's hit is judged unless its
    // utterance already held one of its hits or gave a command: a warped lane's hit that came first and
    // gave none must not take the unwarped verdict's place (below).
    constexpr long kNever = std::numeric_limits<long>::min() / 2;
    const bool by_unwarped = hit.lane == unwarped;
    if (by_unwarped ? (hit.end - unwarped_end < kRedetectSamples || hit.end - command_end < kRedetectSamples)
                    : hit.end - group_end < kRedetectSamples)
      continue;
    // Every phrase competes for the hit's audio, not only those the keyword search hit: the search
    // reports the first phrase whose last state scores well enough, and "start cutting" and "stop
    // cutting" share most of their phones, so it named the wrong one for espeak-ng's British voices.
    // Hits overlapping this one are the same utterance, judged once.
    // With several lanes, the next phrase said straight after ("go forward ten meters") may begin a
    // frame before this one ends in another lane's search: only hits ending near this one's end merge.
    long end = hit.end;
    long unwarped_begin = by_unwarped ? hit.begin : 0, unwarped_to = by_unwarped ? hit.end : kNever;
    while (!pending.empty() && pending.front().begin < hit.end && pending.front().end - hit.end < kRedetectSamples) {
      const PendingHit& other = pending.front();
      end = std::max(end, other.end);
      if (other.lane == unwarped) {
        unwarped_begin = unwarped_to == kNever ? other.begin : std::min(unwarped_begin, other.begin);
        unwarped_to = std::max(unwarped_to, other.end);
      }
      pending.erase(pending.begin());
    }
    group_end = end;
    if (unwarped_to != kNever) unwarped_end = unwarped_to;
    window_scores.clear();
    const auto detection = [&](const Verdict& verdict, bool by_warps) {
      VoiceDetection d{static_cast<double>(samples) / kVoiceSampleRate, verdict.phrase->command, verdict.phrase->phrase};
      d.verification_score = verdict.log_ratio;
      d.command_margin = verdict.margin;
      d.phrase_score = verdict.phrase_log_ratio;
      d.phrase_margin = verdict.phrase_margin;
      d.level_db = verdict.level_db;
      d.garbage_score = verdict.garbage_log_ratio;
      d.garbage_margin = verdict.garbage_margin;
      d.phrase_duration_s = verdict.phrase_frames / 100.0;
      d.garbage_duration_s = verdict.garbage_frames / 100.0;
      d.unwarped_hit = unwarped_to != kNever;
      d.by_warps = by_warps;
      d.hit_phrase = config.phrases[hit.phrase].phrase;
      d.hit_begin_s = static_cast<double>(by_warps || unwarped_to == kNever ? hit.begin : unwarped_begin) / kVoiceSampleRate;
      d.hit_end_s = static_cast<double>(by_warps || unwarped_to == kNever ? end : unwarped_to) / kVoiceSampleRate;
      d.window_begin_s = static_cast<double>(verdict.from) / kVoiceSampleRate;
      const auto alignment = [&](const Verdict::Words& w) {
        VoiceDetection::Alignment a;
        if (w.first < 0) return a;
        const auto at = [&](int frame) { return static_cast<double>(verdict.from + frame * kSamplesPerFrame) / kVoiceSampleRate; };
        a.begin_s = at(w.first);
        a.first_word_end_s = at(w.first_word_last + 1);
        a.end_s = at(w.last + 1);
        a.first_word_ratio = w.first_word_ratio;
        a.rest_ratio = w.rest_ratio;
        a.garbage_score = w.garbage_ratio;
        return a;
      };
      d.aligned = alignment(verdict.aligned);
      d.rival = alignment(verdict.rival);
      return d;
    };
    std::optional<VoiceDetection> command, refused;
    // The unwarped lane's verdict, over its own hits' window, as a spotter with warps [1.0] judges it: a
    // voice the model already fits keeps its commands, which the best-over-warps judgement below lost
    // when another phrase's best warp closed the margin (docs/voice.md, session 38).
    if (unwarped_to != kNever)
      if (const Verdict v = verify(unwarped_begin, unwarped_to, {unwarped}, kVerifyBeforeSamples); v.phrase)
        (verification_accepts(config, detection(v, false)) ? command : refused) = detection(v, false);
    // Only where it gives no command do the warped lanes judge (Lee & Rose 1998's warps, each phrase at
    // its best warp, the unwarped lane's scores among them): where it had no hit of its own, aligned no
    // phrase, or refused one on its scores, level or duration with every margin met: the model may fit
    // the voice badly. A phrase it refused by a margin stands refused: it heard two commands close
    // together, and the warps must not pick one (espeak-ng en+m1's "start cutting" is within 2.5 of
    // "stop cutting" unwarped; the best warp made it a stop, a wrong command). Nor is a command taken
    // that the unwarped lane's best phrase on the same window does not name: dropped, not guessed.
    const bool ambiguous_unwarped = refused && !margins_met(config, *refused);
    if (!command && !ambiguous_unwarped && lanes.size() > 1) {
      std::vector<std::size_t> all(lanes.size());
      for (std::size_t l = 0; l < all.size(); ++l) all[l] = l;
      if (const Verdict v = verify(hit.begin, end, all, kVerifyBeforeSamples); v.phrase) {
        const bool disagree = v.unwarped_best && v.unwarped_best->command != v.phrase->command;
        if (!disagree && verification_accepts(config, detection(v, true)))
          command = detection(v, true);
        else if (!disagree && !refused)
          refused = detection(v, true);
      }
    }
    if (command) {
      command_end = end;
      accepted.push_back(*command);
    } else if (report_refused && refused) {
      accepted.push_back(*refused);
    }
  }
}

bool verification_accepts(const VoiceConfig& config, const VoiceDetection& d) {
  if (!config.verify_min_log_ratio) return true;
  if (!margins_met(config, d)) return false;
  if (config.verify_min_level_db && !(d.level_db >= *config.verify_min_level_db)) return false;
  // Where the phrase is not said, the garbage grammar explains the audio with its phone loop and
  // squeezes the phrase into the fewest frames it can: too short a phrase is none.
  if (config.verify_min_phrase_seconds && !(d.garbage_duration_s >= *config.verify_min_phrase_seconds)) return false;
  // Said on its own, the whole window passes; said inside other words, which the whole window's
  // grammar can explain only with silence, the garbage model's ratio (the words explained by its phone
  // loop) or the phrase's own frames.
  // The garbage ratio's threshold may be the phrase's own: the phrases' ratios are not on one scale.
  auto garbage_min = config.verify_min_garbage_log_ratio;
  if (const auto p = std::find_if(config.phrases.begin(), config.phrases.end(), [&](const VoicePhrase& q) { return q.phrase == d.phrase; });
      garbage_min && p != config.phrases.end() && p->verify_min_garbage_log_ratio)
    garbage_min = p->verify_min_garbage_log_ratio;
  return d.verification_score >= *config.verify_min_log_ratio || (garbage_min && d.garbage_score >= *garbage_min) ||
         (config.verify_min_phrase_log_ratio && d.phrase_score >= *config.verify_min_phrase_log_ratio);
}

std::vector<VoiceDetection> spot_commands(const VoiceConfig& config, std::span<const std::int16_t> samples) {
  KeywordSpotter spotter{config};
  std::vector<VoiceDetection> all;
  constexpr std::size_t kBlock = 512;  // 32 ms, what a microphone read typically returns
  for (std::size_t at = 0; at < samples.size(); at += kBlock) {
    const auto found = spotter.process(samples.subspan(at, std::min(kBlock, samples.size() - at)));
    all.insert(all.end(), found.begin(), found.end());
  }
  const auto last = spotter.finish();
  all.insert(all.end(), last.begin(), last.end());
  return all;
}

}  // namespace tachi::sensor
