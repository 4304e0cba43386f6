#include "tachi/viewer/mesh_file.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

namespace tachi::viewer {
namespace {
constexpr float kFramedDrop_m = 3.0f;  // framing() shows what hangs within this of the top

bool parse_float(std::string_view text, float& value) {
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  return ec == std::errc() && end == text.data() + text.size();
}

// "12", "12/3", "12/3/4" or "12//4": the vertex index, 1-based, negative relative to the end.
bool parse_index(std::string_view text, std::size_t vertices, std::uint32_t& index) {
  text = text.substr(0, text.find('/'));
  long long value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size() || value == 0) return false;
  const long long resolved = value > 0 ? value - 1 : static_cast<long long>(vertices) + value;
  if (resolved < 0 || resolved >= static_cast<long long>(vertices)) return false;
  index = static_cast<std::uint32_t>(resolved);
  return true;
}
}  // namespace

std::optional<Mesh> read_obj(const std::filesystem::path& file, std::string& error) {
  std::ifstream in{file};
  if (!in) {
    error = file.string() + ": cannot read";
    return std::nullopt;
  }
  Mesh mesh;
  std::map<std::string, std::uint16_t, std::less<>> groups;
  std::uint16_t group = 0;
  std::string line;
  std::vector<std::uint32_t> face;
  for (std::size_t number = 1; std::getline(in, line); ++number) {
    const auto fail = [&](const std::string& what) {
      error = file.string() + ":" + std::to_string(number) + ": " + what;
      return std::nullopt;
    };
    std::istringstream words{line};
    std::string tag;
    if (!(words >> tag) || tag[0] == '#') continue;
    if (tag == "v") {
      std::string x, y, z;
      Eigen::Vector3f p;
      if (!(words >> x >> y >> z) || !parse_float(x, p.x()) || !parse_float(y, p.y()) || !parse_float(z, p.z()))
        return fail("a vertex needs three numbers");
      if (!p.allFinite()) return fail("non-finite vertex");
      mesh.positions.push_back(p);
    } else if (tag == "f") {
      face.clear();
      for (std::string corner; words >> corner;) {
        std::uint32_t index = 0;
        if (!parse_index(corner, mesh.positions.size(), index)) return fail("bad vertex index '" + corner + "'");
        face.push_back(index);
      }
      if (face.size() < 3) return fail("a face needs three vertices");
      for (std::size_t k = 1; k + 1 < face.size(); ++k) {
        mesh.triangles.push_back({face[0], face[k], face[k + 1]});
        mesh.groups.push_back(group);
      }
    } else if (tag == "g" || tag == "o") {
      std::string name;
      std::getline(words >> std::ws, name);
      group = groups.emplace(name, static_cast<std::uint16_t>(groups.size())).first->second;
    }
  }
  if (mesh.triangles.empty()) {
    error = file.string() + ": no faces";
    return std::nullopt;
  }
  return mesh;
}

View framing(const Mesh& mesh, View view) {
  float top = -std::numeric_limits<float>::infinity();
  for (const auto& p : mesh.positions) top = std::max(top, p.y());
  Eigen::Vector3f low = Eigen::Vector3f::Constant(std::numeric_limits<float>::infinity());
  Eigen::Vector3f high = -low;
  for (const auto& p : mesh.positions) {
    if (p.y() < top - kFramedDrop_m) continue;
    low = low.cwiseMin(p);
    high = high.cwiseMax(p);
  }
  if (!low.allFinite() || !high.allFinite()) return view;
  view.centre = 0.5f * (low + high);
  view.metres_across = std::max(1.2f * std::max(high.x() - low.x(), high.y() - low.y()), 0.1f);
  return view;
}

}  // namespace tachi::viewer
