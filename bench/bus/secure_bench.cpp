// Latency cost of DDS Security (docs/benchmarks.md, "DDS Security"): round trips between
// two processes on loopback, plain and then authenticated + access-controlled + encrypted, in the
// same run. The ping is a StrokeSample written as the filter; the echo a ClothState written as the
// simulator (small: 12 B of positions; large: a 128x128 cloth, 196 KB), read back by the "filter".
// Prints medians and p99 per mode and the secure/plain ratios.
#include "tachi/bus/topics.hpp"
#include "tachi/common/app.hpp"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <thread>
#include <vector>

extern char** environ;
using namespace std::chrono_literals;
namespace bus = tachi::bus;

namespace {

struct Options {
  std::string pki;
  std::string role = "ping";
  unsigned domain = 195;
  bool secure = false;
  unsigned count = 2000;
  unsigned floats = 3;
};

// The echo side: every stroke sample comes back as a cloth state of `floats` floats with its frame.
int echo(const Options& o) {
  bus::Participant dds{o.domain, {}, o.secure ? bus::Security{o.pki, "sim"} : bus::Security{}};
  bus::Reader<tachi_msg_StrokeSample> in{dds, bus::topics::stroke};
  bus::Writer<tachi_msg_ClothState> out{dds, bus::topics::cloth_state};
  std::vector<float> positions(o.floats, 0.5F);
  tachi_msg_ClothState state{};
  state.positions._buffer = positions.data();
  state.positions._length = state.positions._maximum = o.floats;
  state.positions._release = false;
  unsigned echoed = 0;
  while (!tachi::common::stop_requested() && echoed < o.count + 10) {
    in.wait_for_data(100ms);
    for (const auto& s : in.take()) {
      state.frame = s->frame;
      out.write(state);
      ++echoed;
    }
  }
  return 0;
}

double percentile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

struct Result {
  double p50_us, p99_us;
};

Result ping(const Options& o, const std::string& self) {
  const std::string domain = std::to_string(o.domain);
  std::vector<std::string> args{self,  "--role", "echo", "--domain", domain, "--count", std::to_string(o.count),
                                "--floats", std::to_string(o.floats), "--pki", o.pki};
  if (o.secure) args.emplace_back("--secure");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t child = 0;
  if (posix_spawn(&child, self.c_str(), nullptr, nullptr, argv.data(), environ) != 0) throw std::runtime_error("spawn failed");

  bus::Participant dds{o.domain, {}, o.secure ? bus::Security{o.pki, "filter"} : bus::Security{}};
  bus::Writer<tachi_msg_StrokeSample> out{dds, bus::topics::stroke};
  bus::Reader<tachi_msg_ClothState> in{dds, bus::topics::cloth_state};
  if (!out.wait_for_readers(1, 30s) || !in.wait_for_writers(1, 30s)) throw std::runtime_error("the echo never matched");
  std::this_thread::sleep_for(300ms);  // let the secure handshakes and key exchange settle
  std::vector<double> rtt_us;
  for (unsigned i = 0; i < o.count + 10; ++i) {
    tachi_msg_StrokeSample s{};
    s.frame = i;
    const auto t0 = std::chrono::steady_clock::now();
    out.write(s);
    bool back = false;
    while (!back && in.wait_for_data(2s)) {
      for (const auto& st : in.take()) back = back || st->frame == i;
    }
    if (!back) throw std::runtime_error("lost an echo");
    if (i >= 10) rtt_us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
  }
  int status = 0;
  waitpid(child, &status, 0);
  return {percentile(rtt_us, 0.5), percentile(rtt_us, 0.99)};
}

}  // namespace

int main(int argc, char** argv) try {
  CLI::App app{"tachi-secure-bench: round-trip latency between two processes, plain vs DDS Security"};
  app.name("tachi-secure-bench");
  Options o;
  app.add_option("--pki", o.pki, "Directory made by scripts/make_test_pki.sh")->required()->check(CLI::ExistingDirectory);
  app.add_option("--role", o.role)->group("")->check(CLI::IsMember({"ping", "echo"}));
  app.add_flag("--secure", o.secure)->group("");
  app.add_option("--domain", o.domain, "DDS domain (plain uses it, secure the next one; default 195)")->check(CLI::Range(0u, 231u));
  app.add_option("--count", o.count, "Round trips per mode and size (default 2000)")->check(CLI::Range(10u, 1'000'000u));
  app.add_option("--floats", o.floats)->group("");
  if (const int rc = tachi::common::parse(app, argc, argv); rc >= 0) return rc;
  tachi::common::install_stop_handlers();
  if (o.role == "echo") return echo(o);

  const std::string self = "/proc/self/exe";
  std::printf("%u round trips each: StrokeSample out, ClothState back; p50 / p99 in microseconds\n", o.count);
  std::printf("%-22s %10s %10s %10s %10s %8s\n", "echo size", "plain p50", "p99", "secure p50", "p99", "ratio");
  const unsigned domain = o.domain;
  for (const unsigned floats : {3u, 3u * 128u * 128u}) {
    o.floats = floats;
    o.secure = false;
    o.domain = domain;
    const Result plain = ping(o, std::filesystem::read_symlink(self).string());
    o.secure = true;
    o.domain = domain + 1;
    const Result secure = ping(o, std::filesystem::read_symlink(self).string());
    std::printf("%-22s %10.0f %10.0f %10.0f %10.0f %7.2fx\n", floats == 3 ? "12 B" : "196 KB (128x128)", plain.p50_us,
                plain.p99_us, secure.p50_us, secure.p99_us, secure.p50_us / plain.p50_us);
  }
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "tachi-secure-bench: %s\n", e.what());
  return 1;
}
