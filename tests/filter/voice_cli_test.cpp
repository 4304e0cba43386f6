// Runs the real tachi-voice executable: file mode output, missing devices, bad input, DDS publication.
#include "paths.hpp"
#include "process.hpp"
#include "scratch_dir.hpp"
#include "tachi/bus/topics.hpp"
#include "voice_fixture.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <csignal>
#include <filesystem>
#include <thread>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
constexpr unsigned kDomain = 71;  // filter/voice tests use 70-89

void write_wav(const fs::path& path, const std::vector<std::int16_t>& samples) {
  std::ofstream out(path, std::ios::binary);
  const auto put = [&](std::uint32_t v, int bytes) {
    for (int i = 0; i < bytes; ++i) out.put(static_cast<char>((v >> (8 * i)) & 0xFF));
  };
  const auto data = static_cast<std::uint32_t>(samples.size() * 2);
  out << "RIFF";
  put(36 + data, 4);
  out << "WAVEfmt ";
  put(16, 4);
  put(1, 2);
  put(1, 2);
  put(16000, 4);
  put(32000, 4);
  put(2, 2);
  put(16, 2);
  out << "data";
  put(data, 4);
  for (auto s : samples) put(static_cast<std::uint16_t>(s), 2);
}

class VoiceCli : public ::testing::Test {
 protected:
  void SetUp() override {
    tachi::sensor::testing::Sequence seq{5};
    seq.pause(0.5);
    seq.say("begin cutting", tachi::sensor::testing::flite_say("begin cutting"));
    seq.pause(1.0);
    seq.say("stop cutting", tachi::sensor::testing::flite_say("stop cutting"));
    seq.pause(0.5);
    seq.noise(100.0);
    write_wav(dir_ / "commands.wav", seq.samples());
  }
  /// config/voice.json with its text `key` replaced by `replacement`, written to dir_/name: one setting tried
  /// against the shipped others. Fails the test when the shipped file no longer holds `key`.
  std::string shipped_config_with(const std::string& key, const std::string& replacement, const std::string& name) {
    std::ifstream in{tachi::test::source_dir() + "/config/voice.json"};
    const std::string json{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
    const auto at = json.find(key);
    if (at == std::string::npos) {
      ADD_FAILURE() << "config/voice.json no longer holds " << key << ": update this test";
    } else {
      std::ofstream{dir_ / name} << json.substr(0, at) << replacement << json.substr(at + key.size());
    }
    return (dir_ / name).string();
  }
  /// `start` then "stop cutting" 2 s later, as the voice says them (synthesised into the build tree's voice
  /// cache, dithered when first made), written to dir_/name.
  std::string start_then_stop(const tachi::sensor::testing::Speaker& speaker, const std::string& start, unsigned seed, double noise,
                              const std::string& name) {
    const std::string cache = tachi::test::binary_dir() + "/voice-cache";
    tachi::sensor::testing::Sequence seq{seed};
    seq.pause(0.5);
    seq.say(start, tachi::sensor::testing::synthesize(speaker, start, false, cache));
    seq.pause(2.0);
    seq.say("stop cutting", tachi::sensor::testing::synthesize(speaker, "stop cutting", false, cache));
    seq.pause(1.5);
    if (noise > 0) seq.noise(noise);
    write_wav(dir_ / name, seq.samples());
    return (dir_ / name).string();
  }
  /// tachi-voice's lines for a WAV, "time,command,phrase".
  static std::vector<std::string> heard(const std::string& wav, const std::vector<std::string>& extra) {
    std::vector<std::string> args{tachi::test::executable("tachi-voice"), "--wav", wav, "--no-dds"};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = tachi::test::run(args, 60s);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    std::istringstream in(r.out);
    std::vector<std::string> lines;
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    return lines;
  }
  tachi::test::ScratchDir dir_{"voice_cli"};
};

TEST_F(VoiceCli, WavModePrintsOneLinePerCommand) {
  const auto r = tachi::test::run({tachi::test::executable("tachi-voice"), "--wav", (dir_ / "commands.wav").string(), "--no-dds"}, 60s);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::istringstream lines(r.out);
  std::string line;
  std::vector<std::string> commands;
  while (std::getline(lines, line)) {
    const auto first = line.find(',');
    const auto second = line.find(',', first + 1);
    ASSERT_NE(second, std::string::npos) << line;
    EXPECT_GT(std::stod(line.substr(0, first)), 0.0) << line;
    commands.push_back(line.substr(first + 1));
  }
  EXPECT_EQ(commands, (std::vector<std::string>{"start,begin cutting", "stop,stop cutting"}));
}

TEST_F(VoiceCli, OtherPhrasesAreConfigurableFromTheCommandLine) {
  const auto r = tachi::test::run({tachi::test::executable("tachi-voice"), "--raw", tachi::sensor::testing::kTestData + "/goforward.raw",
                                   "--start-phrase", "go forward", "--stop-phrase", "ten meters", "--no-dds"},
                                  60s);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // "go forward ten meters": both, in order (the stop phrase follows the start phrase at once).
  const auto start = r.out.find(",start,go forward\n"), stop = r.out.find(",stop,ten meters\n");
  EXPECT_NE(start, std::string::npos) << r.out;
  EXPECT_NE(stop, std::string::npos) << r.out;
  EXPECT_LT(start, stop) << r.out;
}

// A command said inside a sentence, through the executable: the whole-window ratio must explain the words
// around the phrase as silence and rejects it; the garbage-model ratio (verify_min_garbage_log_ratio, on in
// config/voice.json) explains them with its phone loop and accepts it (docs/voice.md). Two espeak-ng voices,
// one sentence for each command, each a file of its own.
TEST_F(VoiceCli, ACommandInsideASentenceIsFoundOnTheGarbageModelRatio) {
  // The shipped gates with the garbage ratio off: the whole window alone.
  const std::string whole_window_config = shipped_config_with(
      "\"verify_min_garbage_log_ratio\": -55", "\"verify_min_garbage_log_ratio\": null", "whole_window.json");
  ASSERT_FALSE(HasFailure());
  struct Case {
    const char* voice;
    const char* sentence;
    const char* heard;
  };
  for (const Case& c : {Case{"en+f2", "right, begin cutting here", ",start,begin cutting\n"},
                        Case{"en+m3", "ok stop cutting the cloth", ",stop,stop cutting\n"}}) {
    tachi::sensor::testing::Sequence seq{7};
    seq.pause(0.5);
    seq.say(c.sentence, tachi::sensor::testing::synthesize({"espeak-ng", c.voice}, c.sentence, false,
                                                           tachi::test::binary_dir() + "/voice-cache"));
    seq.pause(1.0);
    seq.noise(100.0);
    write_wav(dir_ / "sentence.wav", seq.samples());
    const auto voice = [&](const std::vector<std::string>& extra) {
      std::vector<std::string> args{tachi::test::executable("tachi-voice"), "--wav", (dir_ / "sentence.wav").string(),
                                    "--no-dds"};
      args.insert(args.end(), extra.begin(), extra.end());
      return tachi::test::run(args, 60s);
    };
    const auto shipped = voice({});
    ASSERT_EQ(shipped.exit_code, 0) << shipped.err;
    EXPECT_NE(shipped.out.find(c.heard), std::string::npos) << c.voice << ": " << c.sentence << "\n" << shipped.out;
    const auto whole_window = voice({"--config", whole_window_config});
    ASSERT_EQ(whole_window.exit_code, 0) << whole_window.err;
    EXPECT_EQ(whole_window.out, "") << c.voice << ": " << c.sentence;
  }
}

TEST_F(VoiceCli, APitchShiftedVoiceIsHeardThroughTheWarpsAndBadWarpsAreRefused) {
  // sox's pitch shift moves the formants (another vocal-tract length): espeak-ng en-us 1.7 semitones up,
  // clean. tachi-voice with "warps": [0.84, 1.0, 1.19] (VTLN, docs/voice.md session 37: three lanes, each phrase
  // scored at its best warp) hears the command as the shipped [1.0] does, and scores it within a point or
  // better (measured -8.7 against -8.7, and -7.8 against -11.3 in a longer file; synthesis is dithered, so
  // a gain is not asserted); a warp out of range is refused naming the key.
  const std::string warped_config = shipped_config_with("\"warps\": [1.0]", "\"warps\": [0.84, 1.0, 1.19]", "warped.json");
  const std::string bad_config = shipped_config_with("\"warps\": [1.0]", "\"warps\": [1.0, 2.5]", "bad.json");
  ASSERT_FALSE(HasFailure());
  const tachi::sensor::testing::Speaker shifted{"espeak-ng", "en-us", 170};
  tachi::sensor::testing::Sequence seq;
  seq.pause(1.0);
  seq.say("begin cutting", tachi::sensor::testing::synthesize(shifted, "begin cutting", false, tachi::test::binary_dir() + "/voice-cache"));
  seq.pause(2.0);
  write_wav(dir_ / "shifted.wav", seq.samples());
  const auto ratio = [&](const std::vector<std::string>& extra) {
    std::vector<std::string> args{tachi::test::executable("tachi-voice"), "--wav", (dir_ / "shifted.wav").string(), "--no-dds",
                                  "--log-level", "debug"};
    args.insert(args.end(), extra.begin(), extra.end());
    const auto r = tachi::test::run(args, 60s);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find(",start,begin cutting"), std::string::npos) << r.out;
    const auto where = r.err.find("log-likelihood ratio ");
    if (where == std::string::npos) return -1e9;
    return std::stod(r.err.substr(where + std::string("log-likelihood ratio ").size()));
  };
  const double shipped = ratio({}), warped = ratio({"--config", warped_config});
  EXPECT_GT(warped, shipped - 1.0) << "unwarped " << shipped << ", warped " << warped;
  const auto bad = tachi::test::run({tachi::test::executable("tachi-voice"), "--wav", (dir_ / "shifted.wav").string(), "--no-dds", "--config",
                                     bad_config},
                                    60s);
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("warps"), std::string::npos) << bad.err;
}

// The warps, through the executable (the shipped config with "warps": [0.84, 1.0, 1.19]), judged by the
// unwarped lane first and by the warped lanes only where it gives no command (docs/voice.md, session 38):
// espeak-ng en+f2 shifted 3 semitones up: the shipped [1.0] misses its "stop cutting"; the warped lanes
// find it (both commands, in order). Measured in 6 of 6 files (3 syntheses, each dithered anew, x 2 noises)
// and in 5 of 5 fresh voice caches.
TEST_F(VoiceCli, TheWarpedLanesFindWhatTheUnwarpedPassMisses) {
  const std::string warped_config = shipped_config_with("\"warps\": [1.0]", "\"warps\": [0.84, 1.0, 1.19]", "warped.json");
  ASSERT_FALSE(HasFailure());
  const auto commands = [](const std::vector<std::string>& lines) {
    std::vector<std::string> said;
    for (const auto& line : lines) said.push_back(line.substr(line.find(',') + 1));
    return said;
  };
  const std::string shifted = start_then_stop({"espeak-ng", "en+f2", 300}, "begin cutting", 7, 100.0, "shifted.wav");
  EXPECT_EQ(commands(heard(shifted, {"--config", warped_config})), (std::vector<std::string>{"start,begin cutting", "stop,stop cutting"}));
  const auto unwarped = commands(heard(shifted, {}));
  EXPECT_EQ(std::count(unwarped.begin(), unwarped.end(), "stop,stop cutting"), 0) << "the unwarped pass now hears it: find another voice";
}

// espeak-ng en+m1 says "start cutting" without its R: unwarped, it scores within the margin of "stop cutting"
// and is refused; with the warps that refusal should stand (as
// VoiceSpotter.ABritishVoiceSaysTheDefaultCommandsRightAndTheOldStartPhraseIsMissedNotHeardAsStop, unwarped).
// Registered disabled until session 39: the synthesis was dithered from a fresh seed when first made, and with
// 1 of 5 fresh voice caches (and in a fresh-clone CI run) the warps reported "1.568,stop,stop cutting": a wrong
// command (session 38). Since 9d0a9c3 sox synthesises with -R (the same audio in every fresh cache): passed 4 of
// 4 runs, each with the build tree's voice cache deleted first, the two files byte-identical each time.
TEST_F(VoiceCli, TheWarpedLanesKeepTheUnwarpedRefusalOfABritishStart) {
  const std::string warped_config = shipped_config_with("\"warps\": [1.0]", "\"warps\": [0.84, 1.0, 1.19]", "warped.json");
  ASSERT_FALSE(HasFailure());
  const std::string british = start_then_stop({"espeak-ng", "en+m1"}, "start cutting", 11, 0.0, "british.wav");
  for (const auto& line : heard(british, {"--config", warped_config, "--start-phrase", "start cutting"}))  // nothing said before 3 s is a stop
    EXPECT_TRUE(line.find(",stop,") == std::string::npos || std::stod(line) > 3.0) << line;
}

// The first-word margin (verify_min_first_word_margin, docs/voice.md session 40), through tachi-voice-eval on one
// voice of the tune set with the audio it has there: espeak-ng en-us+m6 pitch-shifted, seeds +20000. In 20 dB
// babble it says "that is enough, stop cutting", and the whole window's ratio (-13.6, margin 14.1 over "begin
// cutting") accepts "begin cutting" fitted to the words after the command: a wrong command. Its first word scores
// 10.1 per frame below "stop"'s as the garbage grammar aligns them, and the first-word margin refuses it. One
// decoding: the shipped gates' line, and the same verdicts with the margin off (--first-word-sweep).
TEST_F(VoiceCli, AStopTakenForBeginInBabbleIsRefusedByTheFirstWordMargin) {
  const auto r = tachi::test::run({tachi::test::executable("tachi-voice-eval"), "--speakers", "tune", "--seed-offset", "20000", "--voices",
                                   "en-us+m6", "--variants", "pitch-shifted", "--no-command-seconds", "0", "--first-word-sweep"},
                                  280s);  // ~20 s of CPU; 80-90 s beside other jobs (load 8 on 2 cores)
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("WRONG commands 0 over all conditions"), std::string::npos) << r.out;
  // The margin off: the wrong command is back (if not, the case no longer shows the rule's work: find another).
  const auto off = r.out.find("\n| off | ");
  ASSERT_NE(off, std::string::npos) << r.out;
  std::istringstream row(r.out.substr(off + 1, r.out.find('\n', off + 1) - off - 1));
  std::vector<std::string> cells;
  for (std::string cell; std::getline(row, cell, '|');) cells.push_back(cell);
  ASSERT_GE(cells.size(), 5U) << r.out;
  EXPECT_EQ(std::stoi(cells[4]), 1) << "WRONG with the first-word margin off:\n" << r.out;
}

TEST_F(VoiceCli, MissingDevicesExitWithTheNoDeviceCode) {
  auto r = tachi::test::run({tachi::test::executable("tachi-voice"), "--device", "tachi_no_such_device", "--no-dds"}, 30s);
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.err.find("tachi_no_such_device"), std::string::npos) << r.err;
  r = tachi::test::run({tachi::test::executable("tachi-voice"), "--kinect-mic", "--kinect-index", "15", "--no-dds"}, 30s);
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.err.find("no Kinect found"), std::string::npos) << r.err;
}

TEST_F(VoiceCli, BadInputIsAClearErrorNotACrash) {
  {
    std::ofstream junk(dir_ / "junk.wav");
    junk << "this is not audio";
  }
  auto r = tachi::test::run({tachi::test::executable("tachi-voice"), "--wav", (dir_ / "junk.wav").string(), "--no-dds"}, 30s);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("RIFF"), std::string::npos) << r.err;
  r = tachi::test::run({tachi::test::executable("tachi-voice"), "--no-dds"}, 30s);
  EXPECT_EQ(r.exit_code, 2);
  r = tachi::test::run({tachi::test::executable("tachi-voice"), "--wav", (dir_ / "commands.wav").string(), "--stop-phrase", "stop qzxqzx",
                        "--no-dds"},
                       30s);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("qzxqzx"), std::string::npos) << r.err;
  r = tachi::test::run({tachi::test::executable("tachi-voice"), "--wav", (dir_ / "commands.wav").string(), "--device", "x"}, 30s);
  EXPECT_EQ(r.exit_code, 2);
}

TEST_F(VoiceCli, PublishesCommandsOnTheBus) {
  tachi::bus::Participant dds{kDomain};
  tachi::bus::Reader<tachi_msg_VoiceCommand> reader{dds, tachi::bus::topics::voice_command};
  const auto r = tachi::test::run({tachi::test::executable("tachi-voice"), "--wav", (dir_ / "commands.wav").string(), "--domain",
                                   std::to_string(kDomain), "--wait-readers", "10"},
                                  60s);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::vector<std::pair<int, std::string>> got;
  const auto deadline = std::chrono::steady_clock::now() + 5s;
  while (got.size() < 2 && std::chrono::steady_clock::now() < deadline) {
    reader.wait_for_data(100ms);
    for (const auto& c : reader.take()) got.emplace_back(static_cast<int>(c->command), c->phrase);
  }
  ASSERT_EQ(got.size(), 2U);
  EXPECT_EQ(got[0], std::make_pair(static_cast<int>(tachi_msg_VOICE_START), std::string("begin cutting")));
  EXPECT_EQ(got[1], std::make_pair(static_cast<int>(tachi_msg_VOICE_STOP), std::string("stop cutting")));
}

// The two real processes chained on the bus: tachi-voice's commands open and close tachi-filter's gate.
TEST_F(VoiceCli, DrivesTheFilterGateOverTheBus) {
  constexpr unsigned kChainDomain = 74;
  tachi::bus::Participant dds{kChainDomain};
  tachi::bus::Writer<tachi_msg_RawHandSample> hands{dds, tachi::bus::topics::raw_hand};
  tachi::bus::Reader<tachi_msg_StrokeSample> strokes{dds, tachi::bus::topics::stroke};
  tachi::test::ChildProcess filter{{tachi::test::executable("tachi-filter"), "--domain", std::to_string(kChainDomain), "--gate", "voice"}};
  ASSERT_TRUE(hands.wait_for_readers(1, 10s) && strokes.wait_for_writers(1, 10s)) << "tachi-filter did not join";
  tachi::test::ChildProcess voice{{tachi::test::executable("tachi-voice"), "--wav", (dir_ / "commands.wav").string(), "--domain",
                                   std::to_string(kChainDomain), "--wait-readers", "10"}};
  // Hand samples 100 cm from the sensor until tachi-voice has processed the whole file.
  std::vector<tachi_msg_StrokeSample> got;
  tachi_msg_RawHandSample h{};
  h.tracked = true;
  h.position_m = {0.0F, 0.0F, 1.0F};
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  while (voice.running() && std::chrono::steady_clock::now() < deadline) {
    ++h.frame;
    h.capture_time_ns += 33'333'333;
    hands.write(h);
    std::this_thread::sleep_for(2ms);
    for (const auto& s : strokes.take()) got.push_back(*s);
  }
  EXPECT_EQ(voice.wait(10s), 0) << voice.err();
  for (int i = 0; i < 50; ++i) {  // a few more samples after the stop, then drain
    ++h.frame;
    hands.write(h);
    std::this_thread::sleep_for(2ms);
  }
  strokes.wait_for_data(500ms);
  for (const auto& s : strokes.take()) got.push_back(*s);
  filter.signal(SIGINT);
  EXPECT_EQ(filter.wait(10s), 0) << filter.err();

  ASSERT_FALSE(got.empty());
  std::size_t cutting = 0;
  for (const auto& s : got)
    if (s.gate == tachi_msg_GATE_CUTTING) {
      ++cutting;
      EXPECT_EQ(s.opened_by, tachi_msg_GATE_SOURCE_VOICE);
      EXPECT_EQ(s.stroke_id, 1U);
    }
  EXPECT_GT(cutting, 0U) << "the spoken start never opened the gate";
  EXPECT_EQ(got.back().gate, tachi_msg_GATE_IDLE) << "the spoken stop never closed it";
  EXPECT_EQ(got.back().closed_by, tachi_msg_GATE_SOURCE_VOICE);
  EXPECT_EQ(got.back().stroke_id, 1U);
}

}  // namespace
