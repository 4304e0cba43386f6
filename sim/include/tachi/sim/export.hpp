// A run's files: the cloth as Wavefront OBJ, its sewing pattern as SVG, and summary.json, written by the offline
// and the live modes alike.
#pragma once

#include "tachi/sim/cloth.hpp"
#include "tachi/sim/stroke.hpp"
#include "tachi/sim/summary.hpp"

#include <filesystem>

namespace tachi::sim {

/// Writes the live triangles of the cloth as Wavefront OBJ: v, vt from the rest coordinate, vn (area-weighted
/// normals of the faces around the particle), and the faces in one group per piece ("g piece_N").
/// Throws std::runtime_error naming the file when it cannot be written.
void write_obj(const Cloth& cloth, const std::filesystem::path& file);

/// Writes the sewing pattern of the cloth as SVG: each piece's outline (its boundary edges) in rest
/// coordinates, millimetres, and the cut paths the strokes took. Throws naming the file it cannot write.
void write_pattern_svg(const Cloth& cloth, const StrokeCutter& cutter, const std::filesystem::path& file);

/// Writes dir/cloth.obj and dir/summary.json (creating dir), and dir/pattern.svg when a cutter is given.
/// Throws naming the file that failed.
void export_run(const Summary& summary, const Cloth& cloth, const std::filesystem::path& dir,
                const StrokeCutter* cutter = nullptr);

}  // namespace tachi::sim
