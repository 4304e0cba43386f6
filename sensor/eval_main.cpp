// tachi-sensor-eval: compares a tachi-sensor hand CSV with a ground-truth CSV, or (--random)
// renders and scores a range of randomized clips in memory (tachi/sensor/evaluation.hpp).
#include "eval_cli.hpp"
#include "tachi/common/exit_codes.hpp"

#include <exception>
#include <iostream>

int main(int argc, char** argv) try {
  tachi::sensor::EvaluationOptions options;
  if (const int rc = tachi::sensor::parse_eval_flags(argc, argv, options); rc >= 0) return rc;
  return tachi::sensor::run_evaluation(options, std::cout, std::cerr);
} catch (const std::exception& e) {
  std::cerr << "tachi-sensor-eval: " << e.what() << '\n';
  return tachi::common::kExitFailure;
}
