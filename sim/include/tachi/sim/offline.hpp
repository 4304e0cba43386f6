// The offline driver of tachi-sim (no DDS): build a cloth, step it, export the final mesh (OBJ) and a
// summary (JSON). Options, flag registration, the run and the JSON live here, in the library, so that
// features (cutting: --stroke, --blade) extend OfflineOptions / run_offline / to_json, not main.
#pragma once

#include "tachi/sim/blade.hpp"
#include "tachi/sim/cloth.hpp"
#include "tachi/sim/cloth_solver.hpp"
#include "tachi/sim/collision.hpp"
#include "tachi/sim/material.hpp"
#include "tachi/sim/session.hpp"
#include "tachi/sim/solver.hpp"
#include "tachi/sim/stroke.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace tachi::sim {

struct OfflineOptions {
  ClothConfig cloth;                    ///< --grid, --size-m, --pin
  SolverParams solver;                  ///< --substeps, --iterations
  int steps = 600;                      ///< --steps
  std::filesystem::path export_dir;     ///< --export; empty = summary on stdout only
  std::uint32_t seed = 1;               ///< --seed: out-of-plane jitter that breaks the grid's symmetry
  float jitter_m = 1e-4F;               ///< amplitude of that jitter (0 = perfectly flat start)
  std::vector<Sphere> spheres;          ///< --sphere X Y Z R (repeatable)
  std::optional<GroundPlane> ground;    ///< --ground Y
  std::filesystem::path stroke_file;    ///< --stroke: CSV t,x,y,z cut while stepping (t = seconds from the start)
  Blade blade = Blade::Scalpel;         ///< --blade
  CutMode cut_mode = CutMode::Exact;    ///< --cut-mode (the product's default; grid reproduces seed 000)
  std::optional<float> blade_force_n;   ///< --blade-force: overrides the blade's sharpness force
  SolverKind solver_kind = SolverKind::Pbd;  ///< --solver
  bool substeps_given = false;          ///< --substeps was given (else each solver's own default)
  /// --material and --mass-per-area, --stretch-stiffness, --shear-stiffness, --bend-stiffness, --damping;
  /// nothing: the position-based solver keeps its tuned defaults (Provot's solver uses Material{}).
  std::optional<Material> material;
  std::shared_ptr<const PointCloudCollider> object;  ///< --object / --object-from-recording (loaded by main)
};

/// The session the options describe (cloth, solver, material, blade, object), for offline and live runs.
[[nodiscard]] SessionOptions session_options(const OfflineOptions& options);

/// What a run produced. Keys of to_json(): the contract plus extras.
struct Summary {
  std::size_t particles = 0;
  std::size_t springs = 0;    ///< live springs
  std::size_t triangles = 0;  ///< live triangles
  std::size_t pieces = 0;     ///< connected components over live springs
  float max_strain = 0.0F;    ///< max over live structural springs of length / rest - 1
  int steps = 0;
  double step_ms_median = 0.0;
  double step_ms_p95 = 0.0;
  double step_ms_max = 0.0;
  int columns = 0;
  int rows = 0;
  nlohmann::json extra = nlohmann::json::object();  ///< further keys merged into to_json()'s output
};

/// Registers the offline flags on `app`, writing into `options`. Values are checked at parse time
/// (a bad one names its flag and the allowed range).
void add_offline_flags(CLI::App& app, OfflineOptions& options);

/// Parses "N" or "NxM" (columns x rows, each 2..4096). Nothing for anything else.
[[nodiscard]] std::optional<std::pair<int, int>> parse_grid(const std::string& text);

/// Peak resident bytes per particle of a tachi-sim run: 745-770 measured (maximum RSS of
/// `tachi-sim --offline --grid 512|1024 --steps 1`), rounded up (docs/reliability.md, "Bad configs").
inline constexpr double kPeakBytesPerParticle = 800.0;
/// Memory this process may still use: MemAvailable, or the address-space limit when lower (0: unknown).
[[nodiscard]] std::uint64_t available_memory_bytes();
/// Why a columns x rows cloth will not fit in memory (what it needs, what there is), or nothing.
[[nodiscard]] std::optional<std::string> memory_shortfall(int columns, int rows);

/// Summary as JSON: particles, springs, triangles, pieces, max_strain, steps, step_ms_median, ... + extra.
[[nodiscard]] nlohmann::json to_json(const Summary& summary);

/// Writes the live triangles of the cloth as Wavefront OBJ: v, vt from the rest coordinate, vn (area-weighted
/// normals of the faces around the particle), and the faces in one group per piece ("g piece_N").
/// Throws std::runtime_error naming the file when it cannot be written.
void write_obj(const Cloth& cloth, const std::filesystem::path& file);

/// Summary of the cloth as it is now (no timing).
[[nodiscard]] Summary summarize(const Cloth& cloth);

/// Writes the sewing pattern of the cloth as SVG: each piece's outline (its boundary edges) in rest
/// coordinates, millimetres, and the cut paths the strokes took. Throws naming the file it cannot write.
void write_pattern_svg(const Cloth& cloth, const StrokeCutter& cutter, const std::filesystem::path& file);

/// Adds what the cutting did (fallen_pieces, cut_particles, cut_length_m, cut_line, cut_lines, blade,
/// blade_force_n, topology_version, cut_mode, cut_deviation_cells_max) to a summary; the offline and live
/// modes report the same keys.
void add_cut_summary(Summary& summary, const Cloth& cloth, const StrokeCutter& cutter);
/// Adds what the session layer did (blade_force_n, blade_drag_m, blade_max_contact_force_n, solver,
/// object_points, lowest_y_m) to a summary; the offline and live modes report the same keys.
void add_session_summary(Summary& summary, const Session& session);
/// Sets step_ms_median, step_ms_p95 and step_ms_max from the step times of a run.
void add_step_times(Summary& summary, const std::vector<double>& step_ms);
/// Writes dir/cloth.obj and dir/summary.json (creating dir), and dir/pattern.svg when a cutter is given.
/// Throws naming the file that failed.
void export_run(const Summary& summary, const Cloth& cloth, const std::filesystem::path& dir,
                const StrokeCutter* cutter = nullptr);

/// Runs the offline simulation and, when export_dir is set, writes export_dir/cloth.obj and
/// export_dir/summary.json. Throws std::runtime_error on an I/O failure; options must be valid.
Summary run_offline(const OfflineOptions& options);

}  // namespace tachi::sim
