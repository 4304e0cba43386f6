// cut_stability: the perturbation and re-cut acceptance over many random strokes, every blade and every
// cut mode (the ctest runs a few dozen; this runs the full count for docs/cutting.md, "Cuts that do not
// flip"). For each stroke (random_stroke(seed)): the stroke and the stroke moved by 1e-6 m must give the
// same number of pieces and cut lengths within 1 %; and (--recut) the stroke gone over forward, back and
// forward again must give the same pieces as once.
// Usage: cut_stability [--strokes N] [--first-seed S] [--grid G] [--recut] [--blade B] [--mode M] [--verbose]
//                      [--keep-strokes DIR]   (defaults: 500 strokes from seed 1000, grid 32)
// (--blade, --mode: only that blade or mode; --verbose: the pieces and cut length of both runs of each stroke
// that differs; --keep-strokes: both strokes of each differing pair as CSV in DIR, and in SEED_BLADE_MODE.txt the
// two tachi-sim runs that cut them the same way, run from DIR).
//        cut_stability --blade-table   prints docs/cutting.md's blade table (blade_table(), cut_stability.hpp).
#include "../bench_args.hpp"
#include "tachi/sim/cut_stability.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>
#include <unistd.h>

int main(int argc, char** argv) {
  using namespace tachi::sim;
  int strokes = 500;
  std::uint64_t first_seed = 1000;
  int grid = 32;
  bool recut = false;
  bool verbose = false;
  std::filesystem::path keep;  // where the strokes of each differing pair are written (--keep-strokes)
  std::optional<Blade> only_blade;
  std::optional<CutMode> only_mode;
  const auto scratch = std::filesystem::temp_directory_path() / ("cut_stability_" + std::to_string(::getpid()) + ".csv");
  const char* usage = "usage: cut_stability [--strokes N] [--first-seed S] [--grid G] [--recut] [--blade NAME] "
                      "[--mode exact|grid|delete] [--verbose] [--keep-strokes DIR]\n       cut_stability --blade-table\n";
  tachi::bench::exit_on_help(argc, argv, usage);
  if (argc == 2 && std::string{argv[1]} == "--blade-table") {
    std::fputs(blade_table(scratch).c_str(), stdout);
    std::filesystem::remove(scratch);
    return 0;
  }
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--strokes" && i + 1 < argc) {
      strokes = tachi::bench::int_argument(argv[++i], "cut_stability --strokes", 1, 1000000, usage);
    } else if (a == "--first-seed" && i + 1 < argc) {
      first_seed = static_cast<std::uint64_t>(tachi::bench::int_argument(argv[++i], "cut_stability --first-seed", 0, 2147483647, usage));
    } else if (a == "--grid" && i + 1 < argc) {
      grid = tachi::bench::int_argument(argv[++i], "cut_stability --grid", 4, 512, usage);
    } else if (a == "--recut") {
      recut = true;
    } else if (a == "--verbose") {
      verbose = true;
    } else if (a == "--keep-strokes" && i + 1 < argc) {
      keep = argv[++i];
      std::error_code error;
      std::filesystem::create_directories(keep, error);
      if (error) {
        std::fprintf(stderr, "cut_stability: --keep-strokes %s: %s\n", keep.c_str(), error.message().c_str());
        return 2;
      }
    } else if (a == "--blade" && i + 1 < argc && parse_blade(argv[i + 1])) {
      only_blade = parse_blade(argv[++i]);
    } else if (a == "--mode" && i + 1 < argc && parse_cut_mode(argv[i + 1])) {
      only_mode = parse_cut_mode(argv[++i]);
    } else {
      std::fprintf(stderr, "cut_stability: unknown or incomplete argument '%s'\n%s", a.c_str(), usage);
      return 2;
    }
  }
  const Blade blades[] = {Blade::Razor, Blade::Scalpel, Blade::Utility, Blade::Kitchen, Blade::Hunting, Blade::Worn};
  const CutMode modes[] = {CutMode::Exact, CutMode::Grid, CutMode::Delete};
  std::printf("%s over %d strokes (seeds %llu..), %d x %d, top edge pinned\n",
              recut ? "re-cut (there, back, there vs once)" : "1e-6 m perturbation", strokes,
              static_cast<unsigned long long>(first_seed), grid, grid);
  std::printf("| blade | mode | pieces differ | length differs > 1 %% | largest length difference |\n|---|---|---|---|---|\n");
  int failures = 0;
  for (const Blade blade : blades) {
    if (only_blade && *only_blade != blade) continue;
    for (const CutMode mode : modes) {
      if (only_mode && *only_mode != mode) continue;
      int pieces_differ = 0;
      int length_differs = 0;
      double worst = 0.0;
      for (int k = 0; k < strokes; ++k) {
        const std::uint64_t seed = first_seed + static_cast<std::uint64_t>(k);
        const auto stroke = random_stroke(seed);
        const auto other = recut ? there_back_and_there(stroke) : perturbed(stroke, 1e-6, seed ^ 0x9E3779B97F4A7C15ULL);
        const CutOutcome a = cut_outcome(stroke, blade, mode, grid, scratch);
        const CutOutcome b = cut_outcome(other, blade, mode, grid, scratch);
        const double diff = std::abs(a.cut_length_m - b.cut_length_m) / std::max(a.cut_length_m, 1e-3);
        if (a.pieces != b.pieces) ++pieces_differ;
        if (!recut && diff > 0.01) ++length_differs;
        worst = std::max(worst, diff);
        const bool differs = a.pieces != b.pieces || (!recut && diff > 0.01);
        if (differs && !keep.empty()) {
          // Both strokes, and the two tachi-sim runs that cut them as cut_outcome did (its cloth, steps and one
          // thread: tachi-sim's default threads differ by machine, and so would the positions).
          const std::string stem = "seed" + std::to_string(seed) + "_" + std::string{to_string(blade)} + "_" +
                                   std::string{to_string(mode)};
          const std::string other_stem = stem + (recut ? "_recut" : "_perturbed");
          write_stroke_csv(stroke, keep / (stem + "_once.csv"));
          write_stroke_csv(other, keep / (other_stem + ".csv"));
          const auto note = keep / (stem + ".txt");
          std::FILE* f = std::fopen(note.c_str(), "w");
          if (f == nullptr) {
            std::fprintf(stderr, "cut_stability: --keep-strokes: cannot write %s: %s\n", note.c_str(), std::strerror(errno));
          } else {
            const auto command = [&](const std::vector<StrokeSample>& s, const std::string& name) {
              std::fprintf(f, "tachi-sim --offline --grid %d --pin top-edge --threads 1 --steps %d --blade %s --cut-mode %s "
                              "--stroke %s.csv --export %s\n",
                           grid, offline_steps(s), std::string{to_string(blade)}.c_str(),
                           std::string{to_string(mode)}.c_str(), name.c_str(), name.c_str());
            };
            command(stroke, stem + "_once");
            command(other, other_stem);
            std::fprintf(f, "# cut_stability: %zu pieces %.4f m once, %zu pieces %.4f m %s (summary.json: pieces, "
                            "cut_length_m)\n",
                         a.pieces, a.cut_length_m, b.pieces, b.cut_length_m, recut ? "there, back and there" : "moved by 1e-6 m");
            std::fclose(f);
          }
        }
        if (verbose && differs) {
          std::printf("seed %llu: %zu pieces %.4f m / %zu pieces %.4f m\n", static_cast<unsigned long long>(seed),
                      a.pieces, a.cut_length_m, b.pieces, b.cut_length_m);
        }
      }
      failures += pieces_differ + length_differs;
      std::printf("| %s | %s | %d | %s | %.2f %% |\n", std::string{to_string(blade)}.c_str(),
                  std::string{to_string(mode)}.c_str(), pieces_differ, recut ? "-" : std::to_string(length_differs).c_str(),
                  100.0 * worst);
      std::fflush(stdout);
    }
  }
  std::filesystem::remove(scratch);
  std::printf("failures: %d\n", failures);
  return failures == 0 ? 0 : 1;
}
