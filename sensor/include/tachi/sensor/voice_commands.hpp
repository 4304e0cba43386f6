// Voice commands for the cutting gate (seed 000 section 5: start and stop cutting by voice instead of by
// the hand's distance, so the hand does not fluctuate at the start and end of a cut).
// This unit is the pure part: which phrases mean what, at which keyword-spotting threshold, and how a
// decoder hypothesis maps back to commands. The decoder itself is voice_spotter.hpp.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace tachi::sensor {

/// Start and Stop drive the cutting gate; Grab and Release make the hand hold the cloth (seed 000 section 2;
/// optional phrases, none by default so the cutting phrases keep their false-alarm figures: add them
/// in the config ({"phrase": "grab cloth", "command": "grab"}) or with --grab-phrase / --release-phrase).
enum class VoiceCommand : std::uint8_t { Start, Stop, Grab, Release };

std::string to_string(VoiceCommand command);  ///< "start" / "stop" / "grab" / "release"
/// The inverse of to_string; nothing for anything else.
std::optional<VoiceCommand> voice_command_from_string(const std::string& name);

/// One key phrase. Two-word phrases by default: a single "stop" false-alarms on ordinary speech
/// (FIELD_NOTES: 5 false alarms on 27.5 s of LibriVox at 1e-20, "stop cutting" none).
struct VoicePhrase {
  std::string phrase;        ///< lower-case words of the pronunciation dictionary, one space apart
  VoiceCommand command = VoiceCommand::Start;
  double threshold = 1e-15;  ///< pocketsphinx kws threshold: larger = fewer detections, fewer false alarms
  /// The second pass's garbage-model acceptance ratio for this phrase (VoiceConfig::verify_min_garbage_log_ratio
  /// when nothing; off for every phrase when that is off). Per phrase because the phrases do not fail alike:
  /// on two tune sets (seeds +0 and +20000) what is not "stop cutting" reaches -56 as "stop cutting" once the
  /// margins, level and duration hold (the CI subset's LibriVox false alarm: -57.6), what is not "begin
  /// cutting" reaches -66 as "begin cutting" ("that is enough, stop cutting": "-nough" ends like "-gin"),
  /// while said commands run from about -95 to -11 for both (docs/voice.md, session 36).
  std::optional<double> verify_min_garbage_log_ratio = std::nullopt;
};

struct VoiceConfig {
  std::string model_dir = "/usr/share/pocketsphinx/model/en-us/en-us";
  std::string dictionary = "/usr/share/pocketsphinx/model/en-us/cmudict-en-us.dict";
  // The defaults are the two-pass spotter (docs/voice.md, "Two passes"): a sensitive keyword search,
  // each hit verified. One pass as before: thresholds 1e-20, phone loop 0.1, no verify_min_log_ratio.
  // "begin cutting", not "start cutting" (docs/voice.md, "Why the start phrase changed"): in non-rhotic
  // voices (espeak-ng en) "start" has no R and the en-us model hears "stop"; "begin" differs from "stop"
  // in every phone and a syllable.
  // "start cutting" stays selectable (--start-phrase "start cutting" or the config).
  // "begin cutting" accepts a lower garbage-model ratio than the top-level one (VoicePhrase): -60, the
  // middle of the stretch from -55 to -66 where no wrong command is added on the tune sets.
  std::vector<VoicePhrase> phrases{{"begin cutting", VoiceCommand::Start, 1e-15, -60.0},
                                   {"stop cutting", VoiceCommand::Stop, 1e-15, std::nullopt}};
  /// pocketsphinx's `-kws_plp`: the probability of its phone loop, the garbage model a key phrase
  /// competes with. Smaller = more detections (and false alarms). pocketsphinx's own 0.1 finds 21% of
  /// commands in white noise at 20 dB SNR; 1e-10 finds 92-95% and, alone, false-alarms on ordinary
  /// speech (3 in 24.7 s of LibriVox), which the second pass removes.
  double phone_loop_probability = 1e-10;
  /// Second pass (keyword verification, voice_spotter.cpp): each keyword hit is accepted only when the
  /// phrase, aligned again to the audio around the hit, scores at least this log-likelihood ratio per
  /// frame of the phrase against a free phone loop. Chosen on the evaluation's sequences (seeds +0)
  /// between -28 and -18, where none of them changes; nothing: no second pass, every hit is a command.
  std::optional<double> verify_min_log_ratio = -20.0;
  /// Second pass: every phrase is scored on the hit's audio, and the best becomes a command only when
  /// its score beats the best phrase of every other command by at least this (log-likelihood ratio per
  /// frame). A hit that could be either command is dropped: a missed command is a repeat, a wrong one
  /// starts or stops a cut the user did not ask for.
  /// 4: chosen with the garbage margin below on tachi-voice-eval --speakers tune --dump (docs/voice.md;
  /// 8 with the phrase margin 2 before the garbage model: 59.4 % found at 20 dB, now 63.5 %, 1 WRONG both).
  double verify_min_margin = 4.0;
  /// Second pass, for a phrase said inside a sentence: a hit whose whole-window ratio misses
  /// verify_min_log_ratio (the words around the phrase are not silence) is still accepted when the
  /// ratio over the phrase's own frames reaches this. Nothing: only the whole-window ratio counts.
  std::optional<double> verify_min_phrase_log_ratio;
  /// Second pass: the phrase-frames ratio must beat every other command's by at least this too, so
  /// that words around a phrase cannot tip one command over another.
  /// 0 (off): the garbage margin below does its work and loses fewer commands (docs/voice.md).
  double verify_min_phrase_margin = 0.0;
  /// Second pass: the phrase's level above the background's floor (dB; voice_spotter.cpp). Babble of
  /// several talkers has no floor below its own level, so a keyword hit in it stands ~0-6 dB above;
  /// a command said to the Kinect stands well above the room. Nothing: no level check. 14: chosen on
  /// the tune set, where it removed every babble false alarm (19 in 300 s before; docs/voice.md).
  std::optional<double> verify_min_level_db = 14.0;
  /// Second pass: the margin over another command once more, each phrase scored with a garbage model
  /// (a free phone loop) before and after it, so that the words around a phrase are explained
  /// (voice_spotter.cpp). Nothing: not checked. 4, as verify_min_margin (0 until session 36): a command
  /// the garbage grammar prefers by less is a coin toss between the commands, as with silence around
  /// them; on the second tune set (seeds +20000) a "begin cutting" said in reverb was reported as "stop
  /// cutting" at 1.4, and the said commands below 4 were 3 of 1,276 (docs/voice.md, session 36).
  std::optional<double> verify_min_garbage_margin = 4.0;
  /// Second pass, the garbage model as an acceptance test: a hit whose whole-window ratio misses
  /// verify_min_log_ratio (a phrase inside a sentence: its grammar must explain the words around it with
  /// silence) is still a command when its garbage-model ratio reaches this; the margins, level and
  /// duration checks hold either way. Nothing: only the whole window. -55: on the tune set's flat stretch
  /// (-50 to -75: WRONG 1, no false alarm; found at 20 dB 62.2 % -> 72.9 % with the duration check), above
  /// the CI subset's one LibriVox false alarm at -57.6 that -60 let through (docs/voice.md).
  std::optional<double> verify_min_garbage_log_ratio = -55.0;
  /// Second pass: the phrase as the garbage grammar aligns it must last at least this (s), whichever
  /// ratio accepts it. Where the phrase is not said, the phone loop explains the audio better and the
  /// decoder squeezes the phrase into nearly the fewest frames it can (tune set: false alarms and wrong
  /// commands median 0.40 s); said, it lasts longer (median 0.7 s, three in four above 0.57 s).
  /// Nothing: not checked. 0.5: chosen on the tune set (docs/voice.md).
  std::optional<double> verify_min_phrase_seconds = 0.5;
  /// Second pass: the first word's margin over the other command's. "begin cutting" and "stop cutting"
  /// share "cutting", so the commands differ in their first words only; where noise, reverb or the words
  /// of a sentence blur the first word, the whole phrase's scores rest on "cutting" and on the words
  /// around it and can favour the wrong command. Each phrase's first word, as the garbage grammar aligns
  /// it (VoiceDetection::Alignment), is scored against the phone loop per frame; a command whose first
  /// word scores more than this below the first word of the best phrase of another command is refused:
  /// word-level verification, as Sukkar et al. (1996) verify keyword strings word by word. Not checked
  /// where either first word is not aligned (no rival: nothing to confuse it with). Nothing: not checked.
  /// -2: on the four tune sets (seeds +0, +20000, and +40000, +60000 in four of the six conditions;
  /// docs/voice.md, session 40) the wrong
  /// commands' first-word margins are -18.0, -14.1, -10.2, -8.2 and then 3.9 to 60.7: any threshold from
  /// -8 to 3.5 refuses the four negative ones (WRONG 9 -> 5) and no false alarm is added; -2 is the
  /// middle of that stretch, not set just past one wrong command's value, and costs 7 of 1,536 found
  /// at 20 dB (0 costs 9; 4 would refuse one more wrong command at 3.9 for 12).
  std::optional<double> verify_min_first_word_margin = -2.0;
  /// Vocal tract length normalisation by frequency warping (Lee & Rose, "A frequency warping approach to
  /// speaker normalization", IEEE Trans. Speech Audio Proc. 6(1), 1998), through pocketsphinx's front end
  /// (`-warp_type inverse_linear -warp_params a`: the mel filters move to the frequencies f * a, so a > 1
  /// fits a shorter vocal tract, higher formants). Per warp, a keyword search and the second pass's
  /// decoders all hear the audio. Each utterance is judged by the unwarped lane (1.0) as one lane would;
  /// only where it gives no command (no hit of its own, no phrase aligned, or a phrase refused on its
  /// scores, level or duration with every margin met) do all the lanes judge it, each phrase at the warp
  /// where it scores best and the commands competing on those scores, and only a command the unwarped
  /// lane's best phrase names too is taken. A phrase the unwarped lane refused by a margin stays refused
  /// (the warps made such a British "start cutting" a stop). Without 1.0 among them, all the lanes judge
  /// every utterance. [1.0]: no warping. Each warp costs one more keyword search and a second pass per hit
  /// the unwarped lane does not accept (docs/voice.md, sessions 37-38). One pass (no
  /// verify_min_log_ratio) searches unwarped: it has no judge for several lanes' hits on one utterance.
  /// Default [1.0]: with [0.84, 1.0, 1.19] and this judgement the tune set found 304 / 384 at 20 dB (282
  /// with [1.0]) but with 4 WRONG (1) and 3 false alarms (0), all from utterances the unwarped lane had no
  /// hit on (docs/voice.md, session 38).
  std::vector<double> warps{1.0};
};

/// Lower-cases and collapses whitespace: " Start   Cutting " -> "start cutting".
std::string normalise_phrase(const std::string& phrase);

/// Why a config is unusable (empty phrase, duplicate phrase, bad threshold, no start or no stop...), or nothing.
std::optional<std::string> validate(const VoiceConfig& config);

/// Parses JSON ({"model_dir", "dictionary", "phone_loop_probability", "verify_min_log_ratio" (null: one
/// pass), "warps" (VTLN warp factors), "phrases": [{"phrase", "command", "threshold"}]}); missing keys keep their defaults. Throws
/// std::invalid_argument naming the key.
VoiceConfig parse_voice_config(const std::string& json_text);
VoiceConfig load_voice_config(const std::string& path);

/// Replaces the phrase(s) of `command` with `phrase` at the threshold the old one had (the CLI's
/// --start-phrase / --stop-phrase).
void set_phrase(VoiceConfig& config, VoiceCommand command, const std::string& phrase);

/// The keyword list pocketsphinx reads (`-kws`): one "phrase /threshold/" line per phrase. All phrases
/// share one list so that one decoder tells them apart.
std::string kws_file_text(const std::vector<VoicePhrase>& phrases);

/// A decoder hypothesis -> the phrases it contains, in order (pocketsphinx returns kws phrases with a
/// trailing space, and may return two when both ended in one block).
std::vector<VoicePhrase> phrases_in_hypothesis(const std::string& hypothesis, const std::vector<VoicePhrase>& phrases);

}  // namespace tachi::sensor
