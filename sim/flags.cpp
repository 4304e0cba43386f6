#include "flags.hpp"

#include <cmath>
#include <map>
#include <string>

namespace tachi::sim {
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
  // The solver's threads (docs/sim.md "Threads"): by default one core is left to the other nodes sharing the machine.
  o.solver.threads = default_solver_threads();
  app.add_option("--threads", o.solver.threads,
                 "Threads of the pbd solver's sweeps (default: the cores but one, at least 1); the positions are the "
                 "same bit for bit for a given count")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  app.add_option("--cut-work-per-step", o.solver.cut_work_per_step,
                 "A cut's tether work done in the cut's step, in visits (docs/sim.md \"Caches\"); the rest goes on in "
                 "even slices of at least as much over at most 12 steps after it (1, the default: nearly all of it spread). "
                 "0: all of it in the step of the cut")
      ->check(CLI::Range(0, 1 << 30))
      ->capture_default_str();
  app.add_option("--repair-per-step", o.solver.repair_per_step,
                 "Particles the tethers' repair after a cut settles per step, all pin groups together, or the "
                 "cloth's particles over --repair-share if that is more (docs/sim.md \"Caches\")")
      ->check(CLI::Range(1, 1 << 30))
      ->capture_default_str();
  app.add_option("--repair-share", o.solver.repair_share,
                 "The share of the particles the repair may settle in a step, 1/N (0: --repair-per-step alone)")
      ->check(CLI::Range(0, 1 << 20))
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


void add_object_flags(CLI::App& app, ObjectOptions& o) {
  app.add_option("--object", o.file, "PLY point cloud (ascii or binary) the cloth collides with (seed 000)")
      ->check(CLI::ExistingFile);
  app.add_option_function<std::string>(
         "--object-pose",
         [&o](const std::string& text) {
           const auto pose = parse_object_pose(text);
           if (!pose) {
             throw CLI::ValidationError("--object-pose", "'" + text + "' is not X,Y,Z[,RX,RY,RZ[,S]] (metres, degrees, scale > 0)");
           }
           o.pose = *pose;
         },
         "Pose of --object in the cloth's frame: X,Y,Z[,RX,RY,RZ[,S]] (metres, degrees about x, y, z; scale)")
      ->default_str("0,0,0");
  app.add_option("--object-from-recording", o.recording,
                 "Fakenect recording whose first depth frames' static scene is the object (what the Kinect saw)")
      ->check(CLI::ExistingDirectory);
  app.add_option_function<std::string>(
         "--workspace-config",
         [&o](const std::string& file) {
           try {
             o.workspace = common::read_workspace_config(file);
           } catch (const std::exception& e) {
             throw CLI::ValidationError("--workspace-config", e.what());
           }
         },
         "tachi-filter config whose workspace maps --object-from-recording's scene to the cloth, so it lands where the "
         "filter puts the hand (tachi run passes filter.config; default: the filter's default mapping)")
      ->check(CLI::ExistingFile);
  app.add_option("--object-influence", o.influence_m, "Distance from an object point within which the cloth is repelled, m")
      ->check(CLI::Range(0.001F, 1.0F))
      ->capture_default_str();
}

}  // namespace tachi::sim
