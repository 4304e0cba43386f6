// Two `tachi run`s on one DDS domain would mix their samples (the second run's hand would cut the
// first run's cloth): the second is refused, naming the live pipeline's nodes, hosts and pids; and a
// run's nodes read only their run's DDS partition, so a sensor outside the run never reaches them. Domains 145 and 146 (tests/launcher owns 120-149, docs/testing.md).
#include "paths.hpp"
#include "process.hpp"
#include "scratch_dir.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <csignal>
#include <future>
#include <filesystem>
#include <fstream>
#include <sstream>

using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {
const std::string kBin = tachi::test::bin_dir();
const std::string kRecordings = tachi::test::recordings_dir();

std::vector<std::string> run_args(const fs::path& out, const std::string& domain) {
  return {kBin + "/tachi", "run", "--recording", kRecordings + "/straight_cut", "--grid", "32", "--domain", domain, "--out",
          out.string(), "--headless", "--settle", "1"};
}

std::string host_name() {
  char name[256] = {};
  ::gethostname(name, sizeof name - 1);
  return name;
}
}  // namespace

TEST(TwoRunsOnOneDomain, TheSecondIsRefusedNamingTheLivePipelineAndTheFirstCutsAlone) {
  tachi::test::ScratchDir dir("tachi_two_runs");
  // One pipeline split over two launchers (docs/dds.md "Several hosts") shares a domain: not refused. On
  // its own domain (146), alongside the runs above: a run mostly waits on the recording's real time.
  auto split = std::async(std::launch::async, [&dir] {
    tachi::test::ChildProcess producers({kBin + "/tachi", "run", "--nodes", "sim", "--recording", kRecordings + "/straight_cut",
                                         "--grid", "16", "--domain", "146", "--out", (dir / "b").string(), "--headless", "--rate", "2"});
    bool sim_up = false;
    for (int i = 0; i < 30 && !sim_up; ++i)
      sim_up = tachi::test::run({kBin + "/tachi", "status", "--domain", "146", "--listen", "1"}, 30s).out.find("tachi-sim") !=
               std::string::npos;
    ASSERT_TRUE(sim_up) << producers.err();
    tachi::test::ChildProcess consumers({kBin + "/tachi", "run", "--nodes", "sensor,filter", "--recording",
                                         kRecordings + "/straight_cut", "--domain", "146", "--out", (dir / "a").string(), "--headless", "--rate", "2"});
    EXPECT_EQ(consumers.wait(120s), 0) << consumers.err();
    EXPECT_EQ(consumers.err().find("already has a live tachi pipeline"), std::string::npos) << consumers.err();
    EXPECT_EQ(producers.wait(120s), 0) << producers.err();
  });
  tachi::test::ChildProcess first(run_args(dir / "first", "145"));
  // Wait for the first pipeline's heartbeats (its nodes are up), however long a loaded machine takes.
  bool up = false;
  for (int i = 0; i < 30 && !up; ++i) {
    const auto status = tachi::test::run({kBin + "/tachi", "status", "--domain", "145", "--listen", "1"}, 30s);
    up = status.exit_code == 0 && status.out.find("tachi-sim") != std::string::npos;
  }
  ASSERT_TRUE(up) << first.err();
  // Once it runs, a stray sensor outside any run (the default partition) plays another recording on the same domain:
  // the run's nodes, in the run's own partition, must never see its hand.
  tachi::test::ChildProcess stray({kBin + "/tachi-sensor", "--recording", kRecordings + "/push", "--loop", "--domain", "145"});
  const auto second = tachi::test::run(run_args(dir / "second", "145"), 60s);
  EXPECT_EQ(second.exit_code, 1) << second.err;
  EXPECT_NE(second.err.find("DDS domain 145 already has a live tachi pipeline: "), std::string::npos) << second.err;
  EXPECT_NE(second.err.find("tachi-sim on host " + host_name() + ", pid "), std::string::npos) << second.err;
  EXPECT_NE(second.err.find("another --domain"), std::string::npos) << second.err;
  EXPECT_FALSE(fs::exists(dir / "second" / "sim.log")) << "no node of the second run started";

  ASSERT_EQ(first.wait(120s), 0) << first.err();
  stray.signal(SIGINT);
  EXPECT_EQ(stray.wait(10s), 0) << stray.err();
  std::ifstream in(dir / "first" / "summary.json");
  const auto s = nlohmann::json::parse(in, nullptr, false);
  EXPECT_EQ(s["run_id"].get<std::string>().size(), 16u) << "every whole run has its own id: " << s.dump();
  std::ifstream index(kRecordings + "/straight_cut/INDEX.txt");
  std::size_t frames = 0;
  for (std::string line; std::getline(index, line);) frames += line.starts_with("d-") ? 1 : 0;
  EXPECT_EQ(s["frames"], frames) << "the stray sensor's heartbeats are not the run's";
  EXPECT_LE(s["hand_samples"].get<std::size_t>(), frames) << "no hand sample of the stray sensor reached the simulator";
  EXPECT_EQ(s["cuts"], 1) << s.dump();
  EXPECT_EQ(s["pieces"], 1);
  EXPECT_NEAR(s["cut_length_m"].get<double>(), 0.645, 0.05) << "straight_cut's own cut, no other hand in it";

  split.get();
}
