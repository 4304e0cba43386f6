#include "tachi/sim/export.hpp"

#include "tachi/common/disk_full.hpp"
#include "tachi/sim/pieces.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>

namespace tachi::sim {

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
      std::string loop = "M";  // appended, not "M" + point(): GCC 12 warns falsely (-Wrestrict) on the temporary
      loop += point(cloth.rest_uv[first]);
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
