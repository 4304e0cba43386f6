// The filter stage's pure parts: tachi-voice's command lines read back, and the catch-up gate of a recovered
// journal (hands wait for the cloth, at most a second).
#include "tachi/filter/node.hpp"
#include "tachi/filter/voice_csv.hpp"

#include <gtest/gtest.h>

#include <sstream>

using namespace std::chrono_literals;
using tachi::filter::CatchUpGate;
using tachi::filter::VoiceCommandKind;

TEST(VoiceCsv, ReadsTachiVoiceOutputSortedByTime) {
  std::istringstream in("time_s,command,phrase\n2.5,stop,stop cutting\n1.0,start,begin cutting\n\n3,grab,grab cloth\n"
                        "3,release,release cloth\n");
  const auto csv = tachi::filter::read_voice_csv(in);
  ASSERT_EQ(csv.commands.size(), 4u);
  EXPECT_TRUE(csv.skipped.empty());
  EXPECT_DOUBLE_EQ(csv.commands[0].time_s, 1.0);
  EXPECT_EQ(csv.commands[0].kind, VoiceCommandKind::Start);
  EXPECT_EQ(csv.commands[1].kind, VoiceCommandKind::Stop);
  EXPECT_EQ(csv.commands[2].kind, VoiceCommandKind::Grab) << "same time: the file's order";
  EXPECT_EQ(csv.commands[3].kind, VoiceCommandKind::Release);
}

TEST(VoiceCsv, SkipsUnknownCommandsAndBadTimesNamingTheLine) {
  std::istringstream in("1.0,start,begin cutting\nsoon,stop,stop cutting\n2.0,jump,jump\n3.0,stop,stop cutting\n");
  const auto csv = tachi::filter::read_voice_csv(in);
  ASSERT_EQ(csv.commands.size(), 2u);
  ASSERT_EQ(csv.skipped.size(), 2u);
  EXPECT_NE(csv.skipped[0].find("line 2"), std::string::npos) << csv.skipped[0];
  EXPECT_NE(csv.skipped[1].find("line 3"), std::string::npos) << csv.skipped[1];
}

TEST(CatchUpGate, AFreshFilterTakesHandsAtOnce) {
  const CatchUpGate::Clock::time_point t0{};
  const CatchUpGate gate{false, t0};
  EXPECT_TRUE(gate.take_hands(t0));
}

TEST(CatchUpGate, ARecoveredFilterWaitsForTheClothOrOneSecond) {
  const CatchUpGate::Clock::time_point t0{};
  CatchUpGate waits_out{true, t0};
  EXPECT_FALSE(waits_out.take_hands(t0 + 999ms));
  EXPECT_TRUE(waits_out.take_hands(t0 + 1s)) << "no simulator: the hands go on against the rest cloth";
  CatchUpGate sees_cloth{true, t0};
  sees_cloth.cloth_seen();
  EXPECT_TRUE(sees_cloth.take_hands(t0 + 1ms));
}
