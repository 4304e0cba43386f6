// The two steps every causal FIR of the smoothers takes (WienerFir in smoothing.cpp, BankedWiener in
// wiener_bank.cpp): keep the newest samples, and sum the taps relative to the newest one.
#pragma once

#include <Eigen/Core>

#include <cstddef>
#include <deque>
#include <span>

namespace tachi::filter {

/// Puts x in front of a newest-first history, which keeps at most `length` samples; true once it holds
/// `length` (the FIR has an output).
inline bool push_history(std::deque<Eigen::Vector3d>& newest_first, const Eigen::Vector3f& x, std::size_t length) {
  newest_first.push_front(x.cast<double>());
  if (newest_first.size() > length) newest_first.pop_back();
  return length > 0 && newest_first.size() == length;
}

/// y_0 + sum_k gains[k - 1] (y_k - y_0) over a newest-first history y, k = 1..gains.size(): the FIR whose taps
/// sum to 1 (gains are its taps after the newest's), summed relative to the newest sample so that a float
/// position ~1 m from the camera loses nothing to the sum.
inline Eigen::Vector3f relative_fir(const std::deque<Eigen::Vector3d>& newest_first, std::span<const double> gains) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (std::size_t k = 1; k <= gains.size(); ++k) sum += gains[k - 1] * (newest_first[k] - newest_first[0]);
  return (newest_first[0] + sum).cast<float>();
}

}  // namespace tachi::filter
