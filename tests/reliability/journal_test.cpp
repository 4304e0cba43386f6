// The simulator's journal (sim/src/journal.cpp): a killed simulator replays what it applied to the
// same cloth, to the bit; the file is bounded, a torn last line is survived, anything else refused.
#include "scratch_dir.hpp"
#include "tachi/sim/journal.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

namespace tachi::sim {
namespace {

SessionOptions small_cloth(CutMode mode = CutMode::Grid) {
  SessionOptions o;
  o.cloth.columns = o.cloth.rows = 16;
  o.cloth.pin = PinMode::TopEdge;
  o.stroke.mode = mode;
  return o;
}

// A hand sweeping across the cloth's middle in 40 samples, one every other step, then idle.
HandInput sample(int i) {
  HandInput h;
  h.session_id = 77;
  h.stroke_id = 1;
  h.time_s = i / 30.0;
  h.position_m = {-0.6F + 0.03F * static_cast<float>(i), 0.02F * std::sin(0.3F * static_cast<float>(i)), 0.0F};
  h.tracked = true;
  h.cutting = i < 40;
  h.sensor_id = 3;  // as journaled below: the Session tells hand sources apart by it
  return h;
}

// Runs samples [from, to) through a session two steps apart, journaling as tachi-sim does. A kill
// between two calls happens right after a journaled sample: what the journal can bring back is the
// state at its last record (steps after it are lost time, not lost cuts).
void run(Session& session, Journal& journal, int from, int to) {
  for (int i = from; i < to; ++i) {
    session.step();
    session.step();
    const HandInput h = sample(i);
    session.on_hand(h);
    journal.append({JournalRecord::Kind::Hand, session.steps(), 3, static_cast<std::int64_t>(i) * 33'333'333, h});
    journal.flush();
  }
}

TEST(Journal, ARecordRoundTripsExactly) {
  JournalRecord r{JournalRecord::Kind::Hand, 12, 3, 1'700'000'000'123'456'789, sample(7)};
  r.hand.position_m.x() = 0.1F + 1e-7F;
  const auto back = parse_record(format_record(r));
  ASSERT_TRUE(back);
  EXPECT_EQ(back->step, 12u);
  EXPECT_EQ(back->time_ns, r.time_ns);
  EXPECT_EQ(back->hand.session_id, 77u);
  EXPECT_EQ(back->hand.position_m, r.hand.position_m);  // bit for bit
  EXPECT_TRUE(back->hand.cutting);
  EXPECT_FALSE(parse_record("h 1 2 3"));
  EXPECT_FALSE(parse_record("h 1 2 3 4 5 0x1p+0 0x1p+0 0x1p+0 16"));
  EXPECT_FALSE(parse_record(format_record(r) + " trailing"));
}

class JournalReplay : public ::testing::TestWithParam<CutMode> {};

TEST_P(JournalReplay, AKilledRunReplaysToTheSameClothAndCuts) {
  test::ScratchDir dir{"journal"};
  const auto path = dir / "sim.journal";
  const SessionOptions options = small_cloth(GetParam());
  Session undisturbed{options};
  {
    Journal journal{dir / "undisturbed.journal", journal_fingerprint(options)};
    run(undisturbed, journal, 0, 60);
  }
  // The same run, "killed" after 25 samples (the Journal and Session simply vanish)...
  {
    Session first{options};
    Journal journal{path, journal_fingerprint(options)};
    run(first, journal, 0, 25);
  }
  // ...restarted: replay, then the remaining samples.
  Session second{options};
  Journal journal{path, journal_fingerprint(options)};
  ASSERT_EQ(journal.recovered().size(), 25u);
  const auto newest = replay(journal.recovered(), second);
  EXPECT_EQ((newest.at({3u, 77u})), 24 * 33'333'333LL);
  run(second, journal, 25, 60);

  EXPECT_GT(undisturbed.cloth().topology_version, Session{options}.cloth().topology_version + 5)
      << "the stroke must really cut";
  EXPECT_EQ(second.cloth().topology_version, undisturbed.cloth().topology_version);
  EXPECT_EQ(second.cutter().total().cut_line, undisturbed.cutter().total().cut_line);
  ASSERT_EQ(second.cloth().particle_count(), undisturbed.cloth().particle_count());
  for (std::size_t i = 0; i < second.cloth().particle_count(); ++i)
    ASSERT_EQ(second.cloth().position[i], undisturbed.cloth().position[i]) << "particle " << i;
}

INSTANTIATE_TEST_SUITE_P(CutModes, JournalReplay, ::testing::Values(CutMode::Grid, CutMode::Exact, CutMode::Delete),
                         [](const ::testing::TestParamInfo<CutMode>& mode) { return std::string(to_string(mode.param)); });

TEST(Journal, ATornLastLineIsDroppedAndAppendingGoesOn) {
  test::ScratchDir dir{"journal"};
  const auto path = dir / "sim.journal";
  {
    Journal journal{path, "f"};
    journal.append({JournalRecord::Kind::EndStroke, 5, 0, 0, {}});
    journal.flush();
  }
  std::ofstream(path, std::ios::app) << "h 6 3 77 12";  // killed mid-write
  {
    Journal journal{path, "f"};
    EXPECT_EQ(journal.recovered().size(), 1u);
    journal.append({JournalRecord::Kind::EndStroke, 9, 0, 0, {}});
  }
  Journal again{path, "f"};
  ASSERT_EQ(again.recovered().size(), 2u);
  EXPECT_EQ(again.recovered()[1].step, 9u);
}

TEST(Journal, AnotherConfigurationOrACorruptRecordIsAnErrorNamingTheFile) {
  test::ScratchDir dir{"journal"};
  const auto path = dir / "sim.journal";
  { Journal journal{path, "grid=16x16"}; }
  try {
    Journal journal{path, "grid=32x32"};
    FAIL() << "a journal of another configuration was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("another configuration"), std::string::npos) << e.what();
  }
  std::ofstream(path, std::ios::app) << "e 1\ngarbage\ne 2\n";
  try {
    Journal journal{path, "grid=16x16"};
    FAIL() << "a corrupt record was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("line 3 is corrupt"), std::string::npos) << e.what();
  }
}

TEST(Journal, IsBounded) {
  test::ScratchDir dir{"journal"};
  Journal journal{dir / "sim.journal", "f", 200};
  int appended = 0;
  while (journal.append({JournalRecord::Kind::EndStroke, 123456, 0, 0, {}}) && appended < 1000) ++appended;
  journal.flush();
  EXPECT_TRUE(journal.full());
  EXPECT_LT(appended, 30);
  EXPECT_LE(std::filesystem::file_size(dir / "sim.journal"), 200u);
}

}  // namespace
}  // namespace tachi::sim
