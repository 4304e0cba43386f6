#include "tachi/sim/offline.hpp"

#include "tachi/common/disk_full.hpp"
#include "tachi/sim/pieces.hpp"
#include "tachi/sim/stroke.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <string>
#include <stdexcept>

#include <sys/resource.h>

namespace tachi::sim {

namespace {

constexpr int kMaxGrid = 4096;

std::optional<int> parse_int(std::string_view s) {
  int value = 0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (ec != std::errc{} || end != s.data() + s.size()) return std::nullopt;
  return value;
}

/// SplitMix64 (Steele, Lea, Flood 2014): the same jitter on every standard library, unlike <random>'s
/// distributions, so an offline run is reproducible across compilers.
std::uint64_t splitmix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30U)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27U)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31U);
}

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(q * static_cast<double>(values.size() - 1) + 0.5);
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

}  // namespace

std::optional<std::pair<int, int>> parse_grid(const std::string& text) {
  const auto x = text.find_first_of("xX");
  const auto columns = parse_int(std::string_view{text}.substr(0, x));
  const auto rows = x == std::string::npos ? columns : parse_int(std::string_view{text}.substr(x + 1));
  if (!columns || !rows) return std::nullopt;
  if (*columns < 2 || *rows < 2 || *columns > kMaxGrid || *rows > kMaxGrid) return std::nullopt;
  return std::pair{*columns, *rows};
}

namespace {

/// --solver, --material and the material's quantities, each checked with validate(Material) so one
/// message names the flag that is out of range.
void add_material_flags(CLI::App& app, OfflineOptions& o) {
  app.add_option_function<std::string>(
         "--solver",
         [&o](const std::string& text) {
           const auto kind = parse_solver_kind(text);
           if (!kind) throw CLI::ValidationError("--solver", "'" + text + "' is not pbd or provot");
           o.solver_kind = *kind;
         },
         "Cloth solver: pbd (position-based, default) or provot (explicit mass-spring with Provot's "
         "deformation constraint, as the seeds; docs/sim.md compares them)")
      ->default_str("pbd");
  app.add_option_function<std::string>(
         "--material",
         [&o](const std::string& text) {
           const auto material = material_preset(text);
           if (!material) {
             throw CLI::ValidationError("--material", "'" + text + "' is not one of " + std::string{material_names()});
           }
           o.material = *material;
         },
         "Material preset: cotton, silk, denim or felt (values and sources in docs/sim.md)");
  struct Field {
    const char* flag;
    float Material::*member;
    const char* help;
  };
  static constexpr Field kFields[] = {
      {"--mass-per-area", &Material::mass_per_area_kg_m2, "Cloth mass per area, kg/m^2 [0.005, 5]"},
      {"--stretch-stiffness", &Material::stretch_n_per_m, "Stretch stiffness per unit width, N/m [1, 1e6]"},
      {"--shear-stiffness", &Material::shear_n_per_m, "Shear stiffness per unit width, N/m [0.01, 1e6]"},
      {"--bend-stiffness", &Material::bend_n_m, "Bending rigidity, N m [1e-9, 1]"},
      {"--damping", &Material::damping_per_s, "Velocity damping (air drag), 1/s [0, 100]"},
  };
  for (const Field& field : kFields) {
    app.add_option_function<float>(
        field.flag,
        [&o, field](float value) {
          Material m = o.material.value_or(Material{});
          m.*field.member = value;
          if (auto bad = validate(m)) throw CLI::ValidationError(field.flag, *bad);
          o.material = m;
        },
        std::string{field.help} + " (overrides --material's value)");
  }
}

}  // namespace

SessionOptions session_options(const OfflineOptions& o) {
  SessionOptions s;
  s.cloth = o.cloth;
  s.solver = o.solver;
  s.solver_kind = o.solver_kind;
  if (o.material) {
    s.material = *o.material;
    apply_material(*o.material, s.cloth, s.solver);
  }
  if (!o.substeps_given) s.solver.substeps = SolverParams{}.substeps;
  if (o.substeps_given) s.provot.substeps = o.solver.substeps;
  s.stroke.blade = o.blade;
  s.blade_force_n = o.blade_force_n;
  s.stroke.mode = o.cut_mode;
  s.object = o.object;
  return s;
}

std::uint64_t available_memory_bytes() {
  std::uint64_t available = 0;
  std::ifstream meminfo{"/proc/meminfo"};
  std::string key;
  std::uint64_t kb = 0;
  std::string unit;
  while (meminfo >> key >> kb >> unit) {
    if (key == "MemAvailable:") {
      available = kb * 1024;
      break;
    }
  }
  // An address-space limit (ulimit -v) binds before physical memory does.
  rlimit limit{};
  if (getrlimit(RLIMIT_AS, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY)
    available = available == 0 ? limit.rlim_cur : std::min<std::uint64_t>(available, limit.rlim_cur);
  return available;
}

std::optional<std::string> memory_shortfall(int columns, int rows) {
  const double need = kPeakBytesPerParticle * static_cast<double>(columns) * static_cast<double>(rows);
  const auto available = static_cast<double>(available_memory_bytes());
  if (available <= 0.0 || need <= available) return std::nullopt;
  char text[200];
  std::snprintf(text, sizeof text, "a %dx%d cloth needs about %.1f GB and this machine has %.1f GB available; use a smaller grid",
                columns, rows, need / 1e9, available / 1e9);
  return text;
}

void add_offline_flags(CLI::App& app, OfflineOptions& o) {
  app.add_option_function<std::string>(
         "--grid",
         [&o](const std::string& text) {
           const auto grid = parse_grid(text);
           if (!grid) {
             throw CLI::ValidationError("--grid", "'" + text + "' is not N or NxM with N, M in 2..4096");
           }
           if (const auto shortfall = memory_shortfall(grid->first, grid->second))
             throw CLI::ValidationError("--grid", *shortfall);
           o.cloth.columns = grid->first;
           o.cloth.rows = grid->second;
         },
         "Particles per side: N (square) or NxM (columns x rows), 2..4096 (live: 2..512)")
      ->default_str("64");
  app.add_option_function<float>(
         "--size-m",
         [&o](float size) {
           o.cloth.width_m = size;
           o.cloth.height_m = size;
         },
         "Side of the square cloth in metres")
      ->check(CLI::Range(0.01F, 100.0F))
      ->default_str("1");
  app.add_option_function<std::string>(
         "--pin",
         [&o](const std::string& text) {
           static const std::map<std::string, PinMode> pins{
               {"corners", PinMode::Corners}, {"top-edge", PinMode::TopEdge}, {"none", PinMode::None}};
           const auto it = pins.find(text);
           if (it == pins.end()) throw CLI::ValidationError("--pin", "'" + text + "' is not corners, top-edge or none");
           o.cloth.pin = it->second;
         },
         "Fixed particles: corners (the two top ones), top-edge or none")
      ->default_str("corners");
  app.add_option("--steps", o.steps, "Number of 1/60 s steps to simulate (live mode: stop after this many, only when given)")
      ->check(CLI::Range(0, 10'000'000))
      ->capture_default_str();
  app.add_option("--export", o.export_dir, "Folder for cloth.obj and summary.json (created if missing)");
  app.add_option("--seed", o.seed, "Seed of the tiny out-of-plane jitter that breaks the grid's symmetry")
      ->capture_default_str();
  app.add_option_function<int>(
         "--substeps",
         [&o](int n) {
           o.solver.substeps = n;
           o.substeps_given = true;
         },
         "Solver sub-steps per 1/60 s step (default: 2 for pbd, 32 for provot)")
      ->check(CLI::Range(1, 512));
  app.add_option("--iterations", o.solver.iterations, "Structural Gauss-Seidel passes per sub-step")
      ->check(CLI::Range(1, 200))
      ->capture_default_str();
  // The solver's threads (issue 25): by default one core is left to the other nodes sharing the machine.
  o.solver.threads = default_solver_threads();
  app.add_option("--threads", o.solver.threads,
                 "Threads of the pbd solver's sweeps (default: the cores but one, at least 1); the positions are the "
                 "same bit for bit for a given count")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  app.add_option_function<std::vector<float>>(
         "--sphere",
         [&o](const std::vector<float>& v) {
           if (v.size() % 4 != 0) throw CLI::ValidationError("--sphere", "needs 4 numbers: X Y Z R");
           for (std::size_t i = 0; i + 3 < v.size(); i += 4) {
             if (!(v[i + 3] > 0.0F) || !std::isfinite(v[i]) || !std::isfinite(v[i + 1]) || !std::isfinite(v[i + 2])) {
               throw CLI::ValidationError("--sphere", "needs X Y Z R with finite centre and R > 0");
             }
             o.spheres.push_back({Eigen::Vector3f{v[i], v[i + 1], v[i + 2]}, v[i + 3]});
           }
         },
         "Sphere collider X Y Z R in metres (repeatable)")
      ->expected(4)
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll);
  app.add_option_function<float>(
         "--ground", [&o](float y) { o.ground = GroundPlane{y}; }, "Ground plane at height Y (metres)")
      ->check(CLI::Range(-1000.0F, 1000.0F));
  app.add_option("--stroke", o.stroke_file,
                 "CSV stroke (header t,x,y,z; seconds from the start, world metres) cut while stepping")
      ->check(CLI::ExistingFile);
  app.add_option_function<std::string>(
         "--blade",
         [&o](const std::string& text) {
           const auto blade = parse_blade(text);
           if (!blade) {
             throw CLI::ValidationError("--blade", "'" + text + "' is not razor, scalpel, utility, kitchen, hunting or worn");
           }
           o.blade = *blade;
         },
         "Blade sharpness (seed 001 Figure 4): razor, scalpel, utility, kitchen, hunting or worn; it cuts only when "
         "its contact force reaches the blade's sharpness force, else it drags the cloth")
      ->default_str("scalpel");
  app.add_option_function<std::string>(
         "--cut-mode",
         [&o](const std::string& text) {
           const auto mode = parse_cut_mode(text);
           if (!mode) throw CLI::ValidationError("--cut-mode", "'" + text + "' is not exact, grid or delete");
           o.cut_mode = *mode;
         },
         "How strokes cut: exact (along the stroke's own path, splitting triangles), grid (seed 000: along grid "
         "lines, eqs. 1-4, for reproducing it) or delete (seed 001: the crossed triangles are deleted, completeCUT)")
      ->default_str("exact");
  app.add_option_function<float>(
         "--blade-force",
         [&o](float n) {
           if (!std::isfinite(n) || n <= 0.0F || n > 1000.0F) {
             throw CLI::ValidationError("--blade-force", "must be a force in (0, 1000] N");
           }
           o.blade_force_n = n;
         },
         "Sharpness force of the blade in N (overrides --blade's; seed 001 Figure 4: razor 0.3-0.4 ... worn 6-11)");
  add_material_flags(app, o);
}

nlohmann::json to_json(const Summary& s) {
  nlohmann::json j{
      {"particles", s.particles},   {"springs", s.springs},       {"triangles", s.triangles},
      {"pieces", s.pieces},         {"max_strain", s.max_strain}, {"steps", s.steps},
      {"step_ms_median", s.step_ms_median}, {"step_ms_p95", s.step_ms_p95}, {"step_ms_max", s.step_ms_max},
      {"columns", s.columns},       {"rows", s.rows},
  };
  for (const auto& [key, value] : s.extra.items()) j[key] = value;
  return j;
}

void write_obj(const Cloth& cloth, const std::filesystem::path& file) {
  std::ofstream out{file};
  if (!out) throw std::runtime_error("cannot write " + file.string());
  out << "# tachi cloth: " << cloth.particle_count() << " particles, " << cloth.alive_triangle_count()
      << " triangles\n";
  char line[128];
  for (const Eigen::Vector3f& p : cloth.position) {
    std::snprintf(line, sizeof line, "v %.6f %.6f %.6f\n", static_cast<double>(p.x()), static_cast<double>(p.y()),
                  static_cast<double>(p.z()));
    out << line;
  }
  const double du = cloth.columns > 1 ? 1.0 / (cloth.columns - 1) : 0.0;
  const double dv = cloth.rows > 1 ? 1.0 / (cloth.rows - 1) : 0.0;
  for (const Eigen::Vector2f& uv : cloth.rest_uv) {
    std::snprintf(line, sizeof line, "vt %.6f %.6f\n", uv.x() * du, 1.0 - uv.y() * dv);
    out << line;
  }
  // Area-weighted vertex normals: the sum of the (unnormalised) face normals around each particle.
  std::vector<Eigen::Vector3f> normal(cloth.particle_count(), Eigen::Vector3f::Zero());
  for (std::size_t t = 0; t < cloth.triangle_count(); ++t) {
    if (cloth.triangle_alive[t] == 0) continue;
    const auto& tri = cloth.triangles[t];
    const Eigen::Vector3f n =
        (cloth.position[tri[1]] - cloth.position[tri[0]]).cross(cloth.position[tri[2]] - cloth.position[tri[0]]);
    for (const std::uint32_t p : tri) normal[p] += n;
  }
  for (Eigen::Vector3f& n : normal) {
    const float length = n.norm();
    n = length > 0.0F && std::isfinite(length) ? Eigen::Vector3f{n / length} : Eigen::Vector3f::UnitZ();
    std::snprintf(line, sizeof line, "vn %.5f %.5f %.5f\n", static_cast<double>(n.x()), static_cast<double>(n.y()),
                  static_cast<double>(n.z()));
    out << line;
  }
  // One group per piece, in piece order, so a modelling tool selects each cut-off piece on its own.
  const Pieces pieces = find_pieces(cloth);
  std::vector<std::vector<std::uint32_t>> faces(pieces.count());
  for (std::uint32_t t = 0; t < cloth.triangle_count(); ++t) {
    if (cloth.triangle_alive[t] != 0) faces[pieces.piece_of[cloth.triangles[t][0]]].push_back(t);
  }
  for (std::size_t piece = 0; piece < faces.size(); ++piece) {
    if (faces[piece].empty()) continue;
    out << "g piece_" << piece << '\n';
    for (const std::uint32_t t : faces[piece]) {
      const auto& tri = cloth.triangles[t];
      out << 'f';
      for (const std::uint32_t p : tri) out << ' ' << p + 1 << '/' << p + 1 << '/' << p + 1;
      out << '\n';
    }
  }
  out.close();  // a full disk may refuse only the last buffer, written here
  if (!out) common::throw_write_error(file, "error while writing " + file.string());
}

void write_pattern_svg(const Cloth& cloth, const StrokeCutter& cutter, const std::filesystem::path& file) {
  std::ofstream out{file};
  if (!out) throw std::runtime_error("cannot write " + file.string());
  const double mm_u = 1000.0 * cloth.spacing_x();
  const double mm_v = 1000.0 * cloth.spacing_y();
  const double width = mm_u * (cloth.columns - 1);
  const double height = mm_v * (cloth.rows - 1);
  constexpr double kMargin = 10.0;
  char buffer[160];
  std::snprintf(buffer, sizeof buffer,
                "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.1fmm\" height=\"%.1fmm\" "
                "viewBox=\"%.1f %.1f %.1f %.1f\">\n",
                width + 2 * kMargin, height + 2 * kMargin, -kMargin, -kMargin, width + 2 * kMargin,
                height + 2 * kMargin);
  out << buffer << "<!-- tachi pattern: piece outlines in rest coordinates (mm) and the cut paths -->\n";
  // A piece's outline: its mesh edges that border one live triangle only, as that triangle's half-edges
  // (a -> b in its winding). Each boundary vertex of a manifold mesh has as many boundary half-edges
  // leaving as arriving, so following them from any one returns to it: one closed subpath per loop (the
  // piece's rim, and one per hole), which cutters and Inkscape can fill (even-odd) and offset.
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> edges;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> half_edges;
  for (std::size_t t = 0; t < cloth.triangle_count(); ++t) {
    if (cloth.triangle_alive[t] == 0) continue;
    const auto& tri = cloth.triangles[t];
    for (std::size_t i = 0; i < 3; ++i) {
      const std::uint32_t a = tri[i];
      const std::uint32_t b = tri[(i + 1) % 3];
      ++edges[{std::min(a, b), std::max(a, b)}];
      half_edges.emplace_back(a, b);
    }
  }
  std::map<std::uint32_t, std::vector<std::uint32_t>> leaving;  // boundary half-edges a -> b, by a
  for (const auto& [a, b] : half_edges)
    if (edges[{std::min(a, b), std::max(a, b)}] == 1) leaving[a].push_back(b);
  const Pieces pieces = find_pieces(cloth);
  std::vector<std::string> outline(pieces.count());
  const auto point = [&](const Eigen::Vector2f& uv) {
    std::snprintf(buffer, sizeof buffer, "%.2f %.2f", uv.x() * mm_u, uv.y() * mm_v);
    return std::string{buffer};
  };
  for (auto& [first, next] : leaving) {
    while (!next.empty()) {
      std::string loop = "M" + point(cloth.rest_uv[first]);
      std::uint32_t at = first;
      bool closed = false;
      while (true) {
        auto& out_edges = leaving[at];
        if (out_edges.empty()) break;  // not manifold here: the chain ends open
        const std::uint32_t to = out_edges.back();
        out_edges.pop_back();
        if (to == first) {
          closed = true;
          break;
        }
        loop += " L" + point(cloth.rest_uv[to]);
        at = to;
      }
      outline[pieces.piece_of[first]] += loop + (closed ? " Z " : " ");
    }
  }
  for (std::size_t piece = 0; piece < outline.size(); ++piece) {
    if (outline[piece].empty()) continue;
    out << "<path id=\"piece_" << piece << "\" fill=\"none\" fill-rule=\"evenodd\" stroke=\"black\" stroke-width=\"0.5\" d=\""
        << outline[piece] << "\"/>\n";
  }
  for (const auto& path : cutter.paths()) {
    if (path.size() < 2) continue;
    out << "<polyline class=\"cut\" fill=\"none\" stroke=\"red\" stroke-width=\"0.3\" stroke-dasharray=\"2 1\" points=\"";
    for (const Eigen::Vector2f& uv : path) out << point(uv) << ' ';
    out << "\"/>\n";
  }
  out << "</svg>\n";
  out.close();  // a full disk may refuse only the last buffer, written here
  if (!out) common::throw_write_error(file, "error while writing " + file.string());
}

Summary summarize(const Cloth& cloth) {
  Summary s;
  s.particles = cloth.particle_count();
  s.springs = cloth.alive_spring_count();
  s.triangles = cloth.alive_triangle_count();
  const Pieces pieces = find_pieces(cloth);
  s.pieces = pieces.count();
  s.max_strain = cloth.max_structural_strain();
  // Whether max_strain is a cloth at rest or a snapshot of one still moving: the kinetic energy of the pieces a
  // pin holds (pieces that fell off are meant to move).
  double held_kinetic = 0.0;
  for (std::size_t i = 0; i < cloth.particle_count(); ++i) {
    if (pieces.pinned[pieces.piece_of[i]] == 0) continue;
    held_kinetic += 0.5 * static_cast<double>(cloth.mass[i]) * static_cast<double>(cloth.velocity[i].squaredNorm());
  }
  s.extra["held_kinetic_energy_j"] = held_kinetic;
  s.columns = cloth.columns;
  s.rows = cloth.rows;
  return s;
}

Summary run_offline(const OfflineOptions& options) {
  Session session{session_options(options)};
  Cloth& cloth = session.cloth_for_setup();
  std::uint64_t state = options.seed;
  for (std::size_t i = 0; i < cloth.particle_count(); ++i) {
    if (cloth.pinned[i] != 0) continue;
    const double unit = static_cast<double>(splitmix64(state) >> 11U) * 0x1.0p-53;  // [0, 1)
    cloth.position[i].z() += options.jitter_m * static_cast<float>(2.0 * unit - 1.0);
  }
  session.set_shapes(options.spheres, options.ground);

  // The stroke is cut while stepping, each sample at its own time (issue 4), through the session's
  // blade (it cuts only once its contact force reaches the blade's sharpness force).
  StrokeFile stroke;
  std::size_t stroke_outliers = 0;
  if (!options.stroke_file.empty()) {
    std::ifstream in{options.stroke_file};
    if (!in) throw std::runtime_error("cannot read " + options.stroke_file.string());
    stroke = parse_stroke_csv(in);
    for (const auto& problem : stroke.problems) spdlog::warn("{} {}; row skipped", options.stroke_file.string(), problem);
    if (stroke.skipped_rows > stroke.problems.size())
      spdlog::warn("{}: {} rows skipped in all", options.stroke_file.string(), stroke.skipped_rows);
    if (!stroke.error.empty()) throw std::runtime_error(options.stroke_file.string() + ": " + stroke.error);
    stroke_outliers = drop_impossible_samples(stroke.samples);
    if (stroke_outliers > 0)
      spdlog::warn("{}: {} samples faster than a hand (> 10 m/s) are outliers, not cut along", options.stroke_file.string(), stroke_outliers);
  }
  std::size_t next_sample = 0;

  std::vector<double> step_ms;
  step_ms.reserve(static_cast<std::size_t>(options.steps));
  const double dt = session_options(options).solver.dt;
  for (int s = 0; s < options.steps; ++s) {
    while (next_sample < stroke.samples.size() && stroke_sample_due(stroke.samples[next_sample].t, s, dt)) {
      const StrokeSample& sample = stroke.samples[next_sample++];
      session.on_hand({1, sample.t, sample.position, true, true});
      if (next_sample == stroke.samples.size()) session.end_stroke();
    }
    const auto t0 = std::chrono::steady_clock::now();
    session.step();
    step_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }

  session.end_stroke();  // a stroke still open when the run ends is cut up to its last applied sample

  Summary summary = summarize(session.cloth());
  summary.steps = options.steps;
  add_cut_summary(summary, session.cloth(), session.cutter());
  add_session_summary(summary, session);
  summary.extra["stroke_samples"] = stroke.samples.size();
  summary.extra["stroke_samples_applied"] = next_sample;
  summary.extra["stroke_rows_skipped"] = stroke.skipped_rows;
  summary.extra["stroke_outliers"] = stroke_outliers;
  add_step_times(summary, step_ms);
  if (!options.export_dir.empty()) export_run(summary, session.cloth(), options.export_dir, &session.cutter());
  return summary;
}

void add_session_summary(Summary& summary, const Session& session) {
  summary.extra["blade_force_n"] = session.blade().params().force_n;
  summary.extra["blade_drag_m"] = session.max_drag_m();
  summary.extra["blade_max_contact_force_n"] = session.max_contact_force_n();
  summary.extra["solver"] = std::string{to_string(session.solver_kind())};
  summary.extra["object_points"] = session.object() ? session.object()->points().size() : 0U;
  // Counted where the cuts are made: a stroke that cut nothing is no cut, one still open at the end is.
  summary.extra["strokes"] = session.strokes();
  summary.extra["cuts"] = session.cuts();
  const Cloth& cloth = session.cloth();
  float lowest = std::numeric_limits<float>::infinity();
  for (std::size_t i = 0; i < cloth.particle_count(); ++i) lowest = std::min(lowest, cloth.position[i].y());
  summary.extra["lowest_y_m"] = cloth.particle_count() > 0 ? lowest : 0.0F;
}


namespace {

/// How far the cut strays from the stroke's path on the cloth, in cells: exact mode measures its cut edges
/// against the segments that made them; grid mode its cut-line particles against the stroke's path; delete
/// mode (no cut edge, holes) reports the grid mode's measure of nothing: 0.
double cut_deviation_cells(const StrokeCutter& cutter) {
  if (const ExactCutter* exact = cutter.exact()) return exact->max_deviation_cells();
  const auto& line = cutter.total().cut_line;
  double worst = 0.0;
  for (const GridCoord g : line) {
    const Eigen::Vector2d p{g.u, g.v};
    double nearest = std::numeric_limits<double>::infinity();
    for (const auto& path : cutter.paths()) {
      for (std::size_t i = 0; i + 1 < path.size(); ++i) {
        const Eigen::Vector2d a = path[i].cast<double>();
        const Eigen::Vector2d d = path[i + 1].cast<double>() - a;
        const double s = d.squaredNorm() > 0.0 ? std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
        nearest = std::min(nearest, (p - (a + s * d)).norm());
      }
      if (path.size() == 1) nearest = std::min(nearest, (p - path[0].cast<double>()).norm());
    }
    if (std::isfinite(nearest)) worst = std::max(worst, nearest);
  }
  return worst;
}

}  // namespace

void add_cut_summary(Summary& summary, const Cloth& cloth, const StrokeCutter& cutter) {
  const StrokeReport& cut = cutter.total();
  nlohmann::json cut_line = nlohmann::json::array();
  for (const GridCoord g : cut.cut_line) cut_line.push_back({g.u, g.v});
  summary.extra["fallen_pieces"] = find_pieces(cloth).fallen();
  summary.extra["cut_particles"] = cut.particles_duplicated;
  summary.extra["cut_length_m"] = cut.cut_length_m;
  summary.extra["cut_line"] = std::move(cut_line);
  summary.extra["cut_lines"] = cut.lines;
  summary.extra["blade"] = std::string{to_string(cutter.options().blade)};
  summary.extra["blade_force_n"] = sharpness(cutter.options().blade).force_n();
  summary.extra["topology_version"] = cloth.topology_version;
  summary.extra["cut_mode"] = std::string{to_string(cutter.options().mode)};
  summary.extra["cut_deviation_cells_max"] = cut_deviation_cells(cutter);
}

void add_step_times(Summary& summary, const std::vector<double>& step_ms) {
  summary.step_ms_median = percentile(step_ms, 0.5);
  summary.step_ms_p95 = percentile(step_ms, 0.95);
  summary.step_ms_max = step_ms.empty() ? 0.0 : *std::max_element(step_ms.begin(), step_ms.end());
}

void export_run(const Summary& summary, const Cloth& cloth, const std::filesystem::path& dir,
                const StrokeCutter* cutter) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error("cannot create " + dir.string() + ": " + ec.message());
  write_obj(cloth, dir / "cloth.obj");
  if (cutter != nullptr) write_pattern_svg(cloth, *cutter, dir / "pattern.svg");
  const auto json_path = dir / "summary.json";
  std::ofstream out{json_path};
  out << to_json(summary).dump(2) << '\n';
  out.close();
  if (!out) common::throw_write_error(json_path, "cannot write " + json_path.string());
}

}  // namespace tachi::sim
