// DDS Security on the bus and on the whole pipeline (docs/reliability.md): peers with credentials
// talk; a participant with no credentials, or with a certificate from another CA, reads nothing and
// injects nothing; an identity whose grant lacks a topic cannot write it; the secure pipeline cuts.
// Every check runs while authorised traffic flows, so "nothing arrived" means "refused", not "idle".
#include "paths.hpp"
#include "process.hpp"
#include "scratch_dir.hpp"
#include "test_pki.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <csignal>
#include <fstream>

using namespace std::chrono_literals;
using tachi::test::ChildProcess;

namespace {
// Domain ids 170-179 belong to this file (docs/testing.md).
const std::string kBin = tachi::test::bin_dir();
const std::string kPeer = tachi::test::executable("bus_peer");
const std::string kRecordings = tachi::test::recordings_dir();

// Two PKIs, made once per ctest run (the TestPki fixture): ours, and another one whose CAs ours does not trust.
struct Pki {
  static std::string ours() { return tachi::test::test_pki("ours"); }
  static std::string foreign() { return tachi::test::test_pki("foreign"); }
};

std::vector<std::string> peer(const std::string& role, unsigned domain, const std::string& pki, const std::string& identity,
                              std::vector<std::string> extra = {}) {
  std::vector<std::string> argv{kPeer, role, "--domain", std::to_string(domain), "--keys", "1", "--rate", "50"};
  if (!pki.empty()) argv.insert(argv.end(), {"--secure", pki, "--identity", identity});
  argv.insert(argv.end(), extra.begin(), extra.end());
  return argv;
}

nlohmann::json last_json_line(const std::string& out) {
  const auto start = out.rfind('{');
  return start == std::string::npos ? nlohmann::json{} : nlohmann::json::parse(out.substr(start), nullptr, false);
}

// An authorised filter -> sim stroke stream, with `intruder` (a subscriber) listening at the same time.
void expect_intruder_reads_nothing(unsigned domain, const std::string& intruder_pki, const std::string& identity) {
  ChildProcess sub(peer("strokes-sub", domain, Pki::ours(), "sim", {"--count", "100", "--timeout", "20"}));
  ChildProcess intruder(peer("strokes-sub", domain, intruder_pki, identity, {"--count", "100", "--timeout", "5"}));
  ChildProcess pub(peer("strokes-pub", domain, Pki::ours(), "filter", {"--count", "100", "--timeout", "20"}));
  EXPECT_EQ(pub.wait(40s), 0) << pub.err();
  EXPECT_EQ(sub.wait(30s), 0) << sub.out() << sub.err();
  EXPECT_EQ(last_json_line(sub.out())["received"], 100) << "the authorised reader must get everything";
  intruder.wait(30s);
  EXPECT_EQ(last_json_line(intruder.out())["received"], 0) << intruder.out() << intruder.err();
}

// An intruder publishing strokes while an authorised publisher does: the reader sees only the
// authorised samples (the intruder's writer never matches).
void expect_intruder_injects_nothing(unsigned domain, const std::string& intruder_pki, const std::string& identity) {
  ChildProcess sub(peer("strokes-sub", domain, Pki::ours(), "sim", {"--count", "50", "--timeout", "20"}));
  ChildProcess intruder(peer("strokes-pub", domain, intruder_pki, identity, {"--count", "50", "--timeout", "6"}));
  ChildProcess pub(peer("strokes-pub", domain, Pki::ours(), "filter", {"--count", "50", "--timeout", "20"}));
  EXPECT_EQ(pub.wait(40s), 0) << pub.err();
  EXPECT_EQ(sub.wait(30s), 0) << sub.out() << sub.err();
  // Exactly the authorised 50, in order and intact: one injected sample would break either count.
  EXPECT_EQ(last_json_line(sub.out())["received"], 50) << sub.out();
  EXPECT_NE(intruder.wait(30s), 0) << intruder.out();
  EXPECT_NE(intruder.err().find("no reader matched"), std::string::npos) << intruder.err();
}
}  // namespace

TEST(SecureBus, AuthorisedNodesTalkAndUnauthenticatedParticipantReadsNothing) {
  expect_intruder_reads_nothing(170, "", "");
}

TEST(SecureBus, ParticipantWithoutCredentialsInjectsNothing) { expect_intruder_injects_nothing(171, "", ""); }

// The foreign "sim" may read strokes by its own (foreign) grant: only its CA keeps it out.
TEST(SecureBus, CertificateFromAnotherCaReadsNothing) {
  expect_intruder_reads_nothing(172, Pki::foreign(), "sim");
}

TEST(SecureBus, CertificateFromAnotherCaInjectsNothing) {
  expect_intruder_injects_nothing(173, Pki::foreign(), "filter");
}

TEST(SecureBus, TheViewerIdentityCannotPublishStrokes) {
  const auto r = tachi::test::run(peer("strokes-pub", 174, Pki::ours(), "viewer", {"--count", "1", "--timeout", "1"}), 30s);
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("create writer on topic tachi/hand/stroke"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("Not Allowed By Security"), std::string::npos) << r.err;
}

TEST(SecureBus, TheMouseIdentityMayPublishStrokes) {
  ChildProcess sub(peer("strokes-sub", 175, Pki::ours(), "sim", {"--count", "20", "--timeout", "20"}));
  ChildProcess pub(peer("strokes-pub", 175, Pki::ours(), "mouse", {"--count", "20", "--timeout", "20"}));
  EXPECT_EQ(pub.wait(40s), 0) << pub.err();
  EXPECT_EQ(sub.wait(30s), 0) << sub.out() << sub.err();
}

TEST(SecureBus, AMissingCredentialFileIsAnErrorNamingIt) {
  std::filesystem::remove(std::filesystem::path(Pki::ours()) / "nobody.cert.pem");
  const auto r = tachi::test::run({kBin + "/tachi-filter", "--domain", "176", "--secure", Pki::ours(), "--identity", "nobody"}, 20s);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("nobody.cert.pem does not exist"), std::string::npos) << r.err;
}

// The recorded straight cut through the whole pipeline (sensor, filter, sim, viewer), every node
// authenticated, access-controlled and encrypted: the same cut as the plain pipeline's test
// (tests/e2e/pipeline_test.cpp).
TEST(SecurePipeline, CutsTheRecordingLikeThePlainOne) {
  tachi::test::ScratchDir out{"secure_pipeline"};
  const std::string d = "177";
  const std::string& pki = Pki::ours();
  // Grid cuts, as the plain pipeline test was written for: this test is about security, not cut modes.
  ChildProcess sim({kBin + "/tachi-sim", "--grid", "32", "--pin", "top-edge", "--cut-mode", "grid", "--domain", d,
                    "--exit-when-idle", "2", "--export", out.path().string(), "--secure", pki});
  ChildProcess viewer({kBin + "/tachi-viewer", "--headless", "--domain", d, "--snapshot", (out / "final.png").string(),
                       "--fps", "10", "--exit-when-idle", "3", "--secure", pki});
  ChildProcess filter({kBin + "/tachi-filter", "--domain", d, "--gate", "threshold", "--secure", pki});
  // An intruder without credentials listens to the strokes the whole time (stopped once the run ended).
  ChildProcess intruder(peer("strokes-sub", 177, "", "", {"--count", "1", "--timeout", "120"}));
  // Twice the recorded pace: nothing here measures it, and the run waits on the recording's clock.
  ChildProcess sensor({kBin + "/tachi-sensor", "--recording", kRecordings + "/straight_cut", "--rate", "2", "--domain", d,
                       "--wait-readers", "1", "--secure", pki});
  const int sensor_exit = sensor.wait(120s);
  const int sim_exit = sim.wait(60s);
  const int viewer_exit = viewer.wait(30s);
  filter.signal(SIGINT);
  const int filter_exit = filter.wait(20s);
  intruder.signal(SIGINT);
  EXPECT_EQ(intruder.wait(10s), 1) << "the intruder received nothing, and says so: " << intruder.out();
  const std::string logs =
      "sensor: " + sensor.err() + "\nfilter: " + filter.err() + "\nsim: " + sim.err() + "\nviewer: " + viewer.err();
  EXPECT_EQ(sensor_exit, 0) << logs;
  EXPECT_EQ(filter_exit, 0) << logs;
  EXPECT_EQ(sim_exit, 0) << logs;
  EXPECT_EQ(viewer_exit, 0) << logs;
  // The viewer (read-only grant) received the secure cloth and drew it.
  EXPECT_TRUE(std::filesystem::exists(out / "final.png")) << logs;
  EXPECT_NE(viewer.err().find("cloth states received"), std::string::npos) << logs;
  EXPECT_EQ(viewer.err().find(" 0 cloth states received"), std::string::npos) << logs;
  std::ifstream in(out / "summary.json");
  const auto summary = nlohmann::json::parse(in, nullptr, false);
  ASSERT_TRUE(summary.is_object()) << logs;
  EXPECT_GT(summary["hand_samples"].get<int>(), 60) << logs;
  EXPECT_GT(summary["cut_particles"].get<int>(), 5) << logs;
  EXPECT_EQ(summary["pieces"], 1) << logs;
  EXPECT_EQ(last_json_line(intruder.out())["received"], 0) << intruder.out();
}
