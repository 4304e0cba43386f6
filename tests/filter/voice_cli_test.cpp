// Runs the real tachi-voice executable: file mode output, missing devices, bad input, DDS publication.
#include "process.hpp"
#include "scratch_dir.hpp"
#include "tachi/bus/topics.hpp"
#include "voice_fixture.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

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
    seq.say("start cutting", tachi::sensor::testing::flite_say("start cutting"));
    seq.pause(1.0);
    seq.say("stop cutting", tachi::sensor::testing::flite_say("stop cutting"));
    seq.pause(0.5);
    seq.noise(100.0);
    write_wav(dir_ / "commands.wav", seq.samples());
  }
  tachi::filter::testing::ScratchDir dir_{"tachi_voice_cli"};
};

TEST_F(VoiceCli, WavModePrintsOneLinePerCommand) {
  const auto r = tachi::test::run({TACHI_VOICE_EXE, "--wav", (dir_ / "commands.wav").string(), "--no-dds"}, 60s);
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
  EXPECT_EQ(commands, (std::vector<std::string>{"start,start cutting", "stop,stop cutting"}));
}

TEST_F(VoiceCli, OtherPhrasesAreConfigurableFromTheCommandLine) {
  const auto r = tachi::test::run({TACHI_VOICE_EXE, "--raw", tachi::sensor::testing::kTestData + "/goforward.raw",
                                   "--start-phrase", "go forward", "--no-dds"},
                                  60s);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find(",start,go forward\n"), std::string::npos) << r.out;
}

TEST_F(VoiceCli, MissingDevicesExitWithTheNoDeviceCode) {
  auto r = tachi::test::run({TACHI_VOICE_EXE, "--device", "tachi_no_such_device", "--no-dds"}, 30s);
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.err.find("tachi_no_such_device"), std::string::npos) << r.err;
  r = tachi::test::run({TACHI_VOICE_EXE, "--kinect-mic", "--kinect-index", "15", "--no-dds"}, 30s);
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_NE(r.err.find("no Kinect found"), std::string::npos) << r.err;
}

TEST_F(VoiceCli, BadInputIsAClearErrorNotACrash) {
  {
    std::ofstream junk(dir_ / "junk.wav");
    junk << "this is not audio";
  }
  auto r = tachi::test::run({TACHI_VOICE_EXE, "--wav", (dir_ / "junk.wav").string(), "--no-dds"}, 30s);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("RIFF"), std::string::npos) << r.err;
  r = tachi::test::run({TACHI_VOICE_EXE, "--no-dds"}, 30s);
  EXPECT_EQ(r.exit_code, 2);
  r = tachi::test::run({TACHI_VOICE_EXE, "--wav", (dir_ / "commands.wav").string(), "--stop-phrase", "stop qzxqzx",
                        "--no-dds"},
                       30s);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("qzxqzx"), std::string::npos) << r.err;
  r = tachi::test::run({TACHI_VOICE_EXE, "--wav", (dir_ / "commands.wav").string(), "--device", "x"}, 30s);
  EXPECT_EQ(r.exit_code, 2);
}

TEST_F(VoiceCli, PublishesCommandsOnTheBus) {
  tachi::bus::Participant dds{kDomain};
  tachi::bus::Reader<tachi_msg_VoiceCommand> reader{dds, tachi::bus::topics::voice_command};
  const auto r = tachi::test::run({TACHI_VOICE_EXE, "--wav", (dir_ / "commands.wav").string(), "--domain",
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
  EXPECT_EQ(got[0], std::make_pair(static_cast<int>(tachi_msg_VOICE_START), std::string("start cutting")));
  EXPECT_EQ(got[1], std::make_pair(static_cast<int>(tachi_msg_VOICE_STOP), std::string("stop cutting")));
}

}  // namespace
