#include "tachi/sensor/depth_model.hpp"

#include <fstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace tachi::sensor {

DepthModel::DepthModel(const Intrinsics& intrinsics, const DisparityFit& fit) : intrinsics_(intrinsics), fit_(fit) {
  for (std::size_t raw = 0; raw < table_.size(); ++raw) {
    const double inv = static_cast<double>(raw) * fit_.a + fit_.b;
    table_[raw] = (raw == 2047 || inv <= 0.0) ? 0.0f : static_cast<float>(1.0 / inv);
  }
}

DepthModel load_calibration(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error("calibration " + file.string() + ": cannot open");
  nlohmann::json j;
  try {
    in >> j;
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error("calibration " + file.string() + ": not JSON: " + e.what());
  }
  if (!j.is_object()) throw std::runtime_error("calibration " + file.string() + ": expected a JSON object");
  Intrinsics k;
  DisparityFit fit;
  const auto number = [&](const char* key, double& out) {
    if (!j.contains(key)) return;
    if (!j[key].is_number()) throw std::runtime_error("calibration " + file.string() + ": \"" + key + "\" is not a number");
    out = j[key].get<double>();
  };
  number("fx", k.fx);
  number("fy", k.fy);
  number("cx", k.cx);
  number("cy", k.cy);
  number("disparity_a", fit.a);
  number("disparity_b", fit.b);
  if (!(k.fx > 0.0) || !(k.fy > 0.0))
    throw std::runtime_error("calibration " + file.string() + ": fx and fy must be > 0");
  if (fit.a == 0.0) throw std::runtime_error("calibration " + file.string() + ": disparity_a must not be 0");
  return DepthModel{k, fit};
}

DepthModel model_for_recording(const std::filesystem::path& recording_dir) {
  const auto file = recording_dir / kCalibrationFile;
  if (std::filesystem::exists(file)) return load_calibration(file);
  return DepthModel{};
}

void save_calibration(const std::filesystem::path& file, const DepthModel& model) {
  const auto& k = model.intrinsics();
  nlohmann::json j{{"fx", k.fx}, {"fy", k.fy}, {"cx", k.cx}, {"cy", k.cy},
                   {"disparity_a", model.fit().a}, {"disparity_b", model.fit().b}};
  std::ofstream out(file);
  if (!out) throw std::runtime_error("calibration " + file.string() + ": cannot write");
  out << j.dump(2) << '\n';
}

}  // namespace tachi::sensor
