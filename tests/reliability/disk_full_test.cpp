// A full disk under `tachi run` (docs/reliability.md, "A full disk"), on real tmpfs mounts: a 2 MB one
// is refused before any node starts; on one that fills up during the run, the run ends with one line
// naming the file and "no space left on device", exit 5, no node restarted, and summary.json written
// (its room is reserved when the run starts). Needs root for mount(8): exit 77 (skipped) otherwise.
// Domain ids 222-223 belong to this file (220 is ChildrenDieWithTheLauncher's).
#include "paths.hpp"
#include "files.hpp"
#include "process.hpp"
#include "scratch_dir.hpp"

#include <gtest/gtest.h>

#include <sys/mount.h>
#include <unistd.h>

#include <fstream>
#include <iostream>
#include <vector>

using namespace std::chrono_literals;
using tachi::test::ChildProcess;
namespace fs = std::filesystem;

namespace {
const std::string kBin = tachi::test::bin_dir();
const std::string kRecordings = tachi::test::recordings_dir();

// A tmpfs of `size` mounted for the test's lifetime.
class Tmpfs {
 public:
  Tmpfs(const std::string& name, const std::string& size) : dir_(name) {
    mounted_ = ::mount("tmpfs", dir_.path().c_str(), "tmpfs", 0, ("size=" + size).c_str()) == 0;
  }
  ~Tmpfs() {
    if (mounted_) ::umount2(dir_.path().c_str(), MNT_DETACH);
  }
  Tmpfs(const Tmpfs&) = delete;
  Tmpfs& operator=(const Tmpfs&) = delete;
  [[nodiscard]] bool mounted() const { return mounted_; }
  [[nodiscard]] const fs::path& path() const { return dir_.path(); }

 private:
  tachi::test::ScratchDir dir_;
  bool mounted_ = false;
};

// Writes `file` until the filesystem refuses more: the disk is now full.
void fill(const fs::path& file) {
  std::ofstream f(file, std::ios::binary);
  const std::vector<char> block(64 * 1024, 'x');
  while (f.write(block.data(), static_cast<std::streamsize>(block.size())) && f.flush()) {
  }
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

std::vector<std::string> run_args(unsigned domain, const fs::path& out) {
  return {kBin + "/tachi", "run", "--recording", kRecordings + "/straight_cut", "--grid", "32", "--domain",
          std::to_string(domain), "--out", out.string(), "--headless", "--settle", "1"};
}
}  // namespace

TEST(DiskFull, TachiRunOnATwoMegabyteTmpfsFailsBeforeStartingAnyNode) {
  Tmpfs disk("tachi_disk_2m", "2m");
  ASSERT_TRUE(disk.mounted());
  ChildProcess launcher(run_args(222, disk.path() / "run"));
  EXPECT_EQ(launcher.wait(30s), 5) << launcher.err();
  EXPECT_NE(launcher.err().find("free, but this run writes up to about"), std::string::npos) << launcher.err();
  EXPECT_EQ(launcher.err().find("started tachi-"), std::string::npos) << launcher.err();
}

TEST(DiskFull, ADiskFillingDuringTheRunEndsItWithOneMessageAndASummaryRestartingNothing) {
  Tmpfs disk("tachi_disk_8m", "8m");  // room for the preflight's estimate (5.5 MB at grid 32 with video)
  ASSERT_TRUE(disk.mounted());
  const fs::path out = disk.path() / "run";
  ChildProcess launcher(run_args(223, out));
  // The launcher logs on stderr: read until it started the sensor, the last node.
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  while (launcher.err().find("started tachi-sensor") == std::string::npos && launcher.running() &&
         std::chrono::steady_clock::now() < deadline)
    launcher.wait_for_output("never printed", 20ms);
  ASSERT_NE(launcher.err().find("started tachi-sensor"), std::string::npos) << launcher.err();
  fill(disk.path() / "filler");  // another program takes the rest of the disk mid-run
  const int code = launcher.wait(60s);
  const std::string& err = launcher.err();
  EXPECT_EQ(code, 5) << err;
  EXPECT_EQ(count(err, "no space left on device"), 1U) << err;  // once, naming the file
  EXPECT_NE(err.find(out.string() + "/"), std::string::npos) << err;
  EXPECT_EQ(err.find(" died "), std::string::npos) << err;  // no node died and was restarted for it
  ASSERT_TRUE(fs::exists(out / "summary.json")) << err;
  const auto summary = tachi::test::read_json(out / "summary.json");
  EXPECT_EQ(summary.at("restarts"), 0);
  EXPECT_NE(summary.at("ended").get<std::string>().find("disk full"), std::string::npos) << summary.dump(2);
}

int main(int argc, char** argv) {
  if (::geteuid() != 0) {
    std::cout << "skip: mounting a tmpfs needs root\n";
    return 77;
  }
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
