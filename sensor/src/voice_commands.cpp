#include "tachi/sensor/voice_commands.hpp"

#include "tachi/common/text_file.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

namespace tachi::sensor {

std::string to_string(VoiceCommand command) {
  switch (command) {
    case VoiceCommand::Start: return "start";
    case VoiceCommand::Stop: return "stop";
    case VoiceCommand::Grab: return "grab";
    case VoiceCommand::Release: return "release";
  }
  return "?";
}

std::optional<VoiceCommand> voice_command_from_string(const std::string& name) {
  for (const VoiceCommand c : {VoiceCommand::Start, VoiceCommand::Stop, VoiceCommand::Grab, VoiceCommand::Release})
    if (to_string(c) == name) return c;
  return std::nullopt;
}

std::string normalise_phrase(const std::string& phrase) {
  std::istringstream words(phrase);
  std::string word, out;
  while (words >> word) {
    for (char& c : word) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if (!out.empty()) out += ' ';
    out += word;
  }
  return out;
}

std::optional<std::string> validate(const VoiceConfig& config) {
  if (config.phrases.empty()) return "phrases: at least one phrase is needed";
  bool start = false, stop = false;
  std::set<std::string> seen;
  for (const auto& p : config.phrases) {
    if (p.phrase.empty() || p.phrase != normalise_phrase(p.phrase))
      return "phrases: \"" + p.phrase + "\" must be non-empty lower-case words separated by single spaces";
    for (char c : p.phrase)
      if (!(std::islower(static_cast<unsigned char>(c)) || c == ' ' || c == '\''))
        return "phrases: \"" + p.phrase + "\" may hold only letters, spaces and apostrophes";
    if (!seen.insert(p.phrase).second) return "phrases: \"" + p.phrase + "\" appears twice";
    if (!std::isfinite(p.threshold) || p.threshold <= 0.0 || p.threshold > 1.0)
      return "phrases: threshold of \"" + p.phrase + "\" must be in (0, 1] (e.g. 1e-15)";
    if (p.verify_min_garbage_log_ratio && std::isnan(*p.verify_min_garbage_log_ratio))
      return "phrases: verify_min_garbage_log_ratio of \"" + p.phrase + "\" must be a number";
    start = start || p.command == VoiceCommand::Start;
    stop = stop || p.command == VoiceCommand::Stop;
  }
  if (!start || !stop) return "phrases: need at least one start and one stop phrase";
  if (!std::isfinite(config.phone_loop_probability) || config.phone_loop_probability <= 0.0 || config.phone_loop_probability > 1.0)
    return "phone_loop_probability must be in (0, 1] (e.g. 1e-10 with the second pass, 0.1 without)";
  if (config.verify_min_log_ratio && std::isnan(*config.verify_min_log_ratio))
    return "verify_min_log_ratio must be a number (or null for no second pass)";
  if (!std::isfinite(config.verify_min_margin) || config.verify_min_margin < 0.0)
    return "verify_min_margin must be a number >= 0 (e.g. 2)";
  if (config.verify_min_phrase_log_ratio && std::isnan(*config.verify_min_phrase_log_ratio))
    return "verify_min_phrase_log_ratio must be a number (or null)";
  if (!std::isfinite(config.verify_min_phrase_margin) || config.verify_min_phrase_margin < 0.0)
    return "verify_min_phrase_margin must be a number >= 0 (e.g. 2)";
  if (config.verify_min_level_db && std::isnan(*config.verify_min_level_db)) return "verify_min_level_db must be a number (or null)";
  if (config.verify_min_garbage_margin && std::isnan(*config.verify_min_garbage_margin))
    return "verify_min_garbage_margin must be a number (or null)";
  if (config.verify_min_garbage_log_ratio && std::isnan(*config.verify_min_garbage_log_ratio))
    return "verify_min_garbage_log_ratio must be a number (or null)";
  if (config.verify_min_phrase_seconds && !(*config.verify_min_phrase_seconds >= 0.0))
    return "verify_min_phrase_seconds must be a number >= 0 (or null)";
  if (config.verify_min_first_word_margin && !std::isfinite(*config.verify_min_first_word_margin))
    return "verify_min_first_word_margin must be a number (or null)";
  // A warp far from 1 moves the mel filters past what any adult vocal tract needs (adults span about
  // 0.8-1.2; Lee & Rose 1998 search 0.88-1.12); the first filter must stay above 0 Hz and the last below
  // the Nyquist frequency.
  if (config.warps.empty()) return "warps must hold at least one warp factor (e.g. [1.0]: no warping)";
  for (std::size_t i = 0; i < config.warps.size(); ++i) {
    if (!(config.warps[i] >= 0.7 && config.warps[i] <= 1.4)) return "warps: each warp factor must be a number in [0.7, 1.4] (e.g. [0.88, 1.0, 1.13])";
    for (std::size_t j = 0; j < i; ++j)
      if (config.warps[j] == config.warps[i]) return "warps: " + std::to_string(config.warps[i]) + " appears twice";
  }
  return std::nullopt;
}

namespace {
[[noreturn]] void fail(const std::string& message) { throw std::invalid_argument("voice config: " + message); }
}  // namespace

VoiceConfig parse_voice_config(const std::string& json_text) {
  using nlohmann::json;
  json root;
  try {
    root = json::parse(json_text);
  } catch (const json::exception& e) {
    fail(std::string("not valid JSON: ") + e.what());
  }
  if (!root.is_object()) fail("the document must be a JSON object");
  VoiceConfig c;
  for (const auto& item : root.items())
    if (item.key() != "model_dir" && item.key() != "dictionary" && item.key() != "phrases" && item.key() != "phone_loop_probability" &&
        item.key() != "verify_min_log_ratio" && item.key() != "verify_min_margin" && item.key() != "verify_min_phrase_log_ratio" &&
        item.key() != "verify_min_phrase_margin" && item.key() != "verify_min_level_db" &&
        item.key() != "verify_min_garbage_margin" && item.key() != "verify_min_garbage_log_ratio" &&
        item.key() != "verify_min_phrase_seconds" && item.key() != "verify_min_first_word_margin" && item.key() != "warps")
      fail("unknown key " + item.key());
  try {
    if (root.contains("model_dir")) c.model_dir = root.at("model_dir").get<std::string>();
    if (root.contains("dictionary")) c.dictionary = root.at("dictionary").get<std::string>();
    if (root.contains("phone_loop_probability")) c.phone_loop_probability = root.at("phone_loop_probability").get<double>();
    if (root.contains("verify_min_log_ratio")) {
      const auto& v = root.at("verify_min_log_ratio");
      if (v.is_null())
        c.verify_min_log_ratio.reset();  // one pass
      else if (v.is_number())
        c.verify_min_log_ratio = v.get<double>();
      else
        fail("verify_min_log_ratio must be a number (e.g. -20) or null (no second pass)");
    }
    if (root.contains("verify_min_margin")) c.verify_min_margin = root.at("verify_min_margin").get<double>();
    for (const auto& [key, target] : {std::pair{"verify_min_phrase_log_ratio", &c.verify_min_phrase_log_ratio},
                                      std::pair{"verify_min_level_db", &c.verify_min_level_db},
                                      std::pair{"verify_min_garbage_margin", &c.verify_min_garbage_margin},
                                      std::pair{"verify_min_garbage_log_ratio", &c.verify_min_garbage_log_ratio},
                                      std::pair{"verify_min_phrase_seconds", &c.verify_min_phrase_seconds},
                                      std::pair{"verify_min_first_word_margin", &c.verify_min_first_word_margin}}) {
      if (!root.contains(key)) continue;
      const auto& v = root.at(key);
      if (v.is_null())
        target->reset();
      else if (v.is_number())
        *target = v.get<double>();
      else
        fail(std::string(key) + " must be a number or null");
    }
    if (root.contains("warps")) {
      const auto& w = root.at("warps");
      if (!w.is_array()) fail("warps must be an array of warp factors (e.g. [0.88, 1.0, 1.13])");
      c.warps.clear();
      for (const auto& a : w) {
        if (!a.is_number()) fail("warps must hold numbers (warp factors, e.g. [0.88, 1.0, 1.13])");
        c.warps.push_back(a.get<double>());
      }
    }
    if (root.contains("verify_min_phrase_margin")) c.verify_min_phrase_margin = root.at("verify_min_phrase_margin").get<double>();
    if (root.contains("phrases")) {
      c.phrases.clear();
      for (const auto& p : root.at("phrases")) {
        for (const auto& item : p.items())
          if (item.key() != "phrase" && item.key() != "command" && item.key() != "threshold" && item.key() != "verify_min_garbage_log_ratio")
            fail("unknown key phrases[]." + item.key());
        VoicePhrase vp;
        vp.phrase = normalise_phrase(p.at("phrase").get<std::string>());
        const std::string command = p.at("command").get<std::string>();
        const auto kind = voice_command_from_string(command);
        if (!kind) fail("phrases[].command must be \"start\", \"stop\", \"grab\" or \"release\" (got \"" + command + "\")");
        vp.command = *kind;
        if (p.contains("threshold")) vp.threshold = p.at("threshold").get<double>();
        if (p.contains("verify_min_garbage_log_ratio")) {
          if (!p.at("verify_min_garbage_log_ratio").is_number()) fail("phrases[].verify_min_garbage_log_ratio must be a number");
          vp.verify_min_garbage_log_ratio = p.at("verify_min_garbage_log_ratio").get<double>();
        }
        c.phrases.push_back(vp);
      }
    }
  } catch (const json::exception& e) {
    fail(e.what());
  }
  if (const auto why = validate(c)) fail(*why);
  return c;
}

VoiceConfig load_voice_config(const std::string& path) {
  return parse_voice_config(common::read_text_file(path, "voice config"));
}

void set_phrase(VoiceConfig& config, VoiceCommand command, const std::string& phrase) {
  double threshold = VoicePhrase{}.threshold;
  std::vector<VoicePhrase> kept;
  for (const auto& p : config.phrases) {
    if (p.command == command)
      threshold = p.threshold;
    else
      kept.push_back(p);
  }
  // The old phrase's own garbage ratio is not carried over: it was measured on that phrase's audio.
  kept.push_back({normalise_phrase(phrase), command, threshold, std::nullopt});
  config.phrases = std::move(kept);
}

std::string kws_file_text(const std::vector<VoicePhrase>& phrases) {
  std::string text;
  for (const auto& p : phrases) {
    char threshold[32];
    std::snprintf(threshold, sizeof threshold, "%g", p.threshold);
    text += p.phrase + " /" + threshold + "/\n";
  }
  return text;
}

std::vector<VoicePhrase> phrases_in_hypothesis(const std::string& hypothesis, const std::vector<VoicePhrase>& phrases) {
  std::string hyp(1, ' ');
  hyp += normalise_phrase(hypothesis);
  hyp += ' ';
  std::vector<std::pair<std::size_t, VoicePhrase>> found;
  for (const auto& p : phrases) {
    std::string needle(1, ' ');
    needle += p.phrase;
    needle += ' ';
    for (std::size_t at = hyp.find(needle); at != std::string::npos; at = hyp.find(needle, at + 1)) found.emplace_back(at, p);
  }
  // In order; where phrases overlap ("stop" inside "stop cutting") the longest one wins.
  std::sort(found.begin(), found.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first < b.first : a.second.phrase.size() > b.second.phrase.size();
  });
  std::vector<VoicePhrase> out;
  std::size_t end = 0;
  for (auto& f : found) {
    if (f.first < end) continue;
    end = f.first + f.second.phrase.size() + 1;
    out.push_back(std::move(f.second));
  }
  return out;
}

}  // namespace tachi::sensor
