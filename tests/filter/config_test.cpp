#include "paths.hpp"
#include "tachi/filter/config.hpp"

#include <gtest/gtest.h>

#include <fstream>

namespace tachi::filter {
namespace {

std::string error_of(const std::string& json) {
  try {
    parse_filter_config(json);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(FilterConfig, EmptyDocumentGivesTheDefaults) {
  const FilterConfig c = parse_filter_config("{}");
  EXPECT_EQ(c.smoother.kind, SmootherKind::WienerBank);
  EXPECT_EQ(c.gate.mode, GateMode::Threshold);
  EXPECT_TRUE(c.workspace.rotation.isApprox(default_mapping().rotation));
}

TEST(FilterConfig, RoundTripsThroughJson) {
  FilterConfig c;
  c.smoother.kind = SmootherKind::MovingAverage;
  c.smoother.moving_average_window = 7;
  c.gate.mode = GateMode::Either;
  c.gate.exit_dwell_samples = 6;
  c.cloth.width_m = 2.0F;
  c.workspace.translation_m = {0.1F, 0.2F, -1.5F};
  const FilterConfig back = parse_filter_config(to_json(c));
  EXPECT_EQ(back.smoother.kind, SmootherKind::MovingAverage);
  EXPECT_EQ(back.smoother.moving_average_window, 7U);
  EXPECT_EQ(back.gate.mode, GateMode::Either);
  EXPECT_EQ(back.gate.exit_dwell_samples, 6);
  EXPECT_FLOAT_EQ(back.cloth.width_m, 2.0F);
  EXPECT_TRUE(back.workspace.translation_m.isApprox(c.workspace.translation_m));
}

TEST(FilterConfig, TheShippedConfigFileParsesToTheBuiltInDefaults) {
  const FilterConfig file = load_filter_config(tachi::test::source_dir() + "/config/filter.json");
  EXPECT_EQ(to_json(file), to_json(FilterConfig{}));
}

TEST(FilterConfig, BadValuesNameTheKey) {
  EXPECT_NE(error_of(R"({"gate": {"enter_distance_m": 0.1, "exit_distance_m": 0.05}})").find("exit_distance_m"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"smoother": {"kind": "kalman"}})").find("smoother.kind"), std::string::npos);
  EXPECT_NE(error_of(R"({"gate": {"mode": "always"}})").find("gate.mode"), std::string::npos);
  EXPECT_NE(error_of(R"({"workspace": {"rotation": [[1,0,0],[0,1,0]]}})").find("rotation"), std::string::npos);
  EXPECT_NE(error_of(R"({"workspace": {"rotation": [[-1,0,0],[0,1,0],[0,0,1]]}})").find("det"), std::string::npos);
  EXPECT_NE(error_of(R"({"smoother": {"beta": "fast"}})").find("smoother.beta"), std::string::npos);
  EXPECT_NE(error_of(R"({"gate": {"enter_distnce_m": 0.1}})").find("unknown key gate.enter_distnce_m"), std::string::npos);
  EXPECT_NE(error_of("{not json").find("not valid JSON"), std::string::npos);
  EXPECT_NE(error_of("[1, 2]").find("object"), std::string::npos);
}

// An integer field takes a whole number its type holds: 5.7e90 once reached a float-to-integer cast
// (undefined behaviour, found by fuzz/config_fuzz.cpp) and -1 wrapped to 2^64-1.
TEST(FilterConfig, IntegerFieldsRefuseNumbersTheyCannotHold) {
  for (const char* bad : {"5.66667e+90", "-1", "2.5", "18446744073709551616", "true"}) {
    const std::string error = error_of(std::string(R"({"smoother": {"moving_average_window": )") + bad + "}}");
    EXPECT_NE(error.find("smoother.moving_average_window"), std::string::npos) << bad << ": " << error;
  }
  EXPECT_NE(error_of(R"({"gate": {"exit_dwell_samples": 3e9}})").find("gate.exit_dwell_samples"), std::string::npos);
  EXPECT_EQ(parse_filter_config(R"({"smoother": {"moving_average_window": 4.0}})").smoother.moving_average_window, 4U);
}

TEST(FilterConfig, MissingFileIsARuntimeError) {
  EXPECT_THROW(load_filter_config("/nonexistent/filter.json"), std::runtime_error);
}

}  // namespace
}  // namespace tachi::filter
