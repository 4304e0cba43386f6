#pragma once
// Reading a number from untrusted JSON into a C++ integer. nlohmann's get<unsigned>() converts with a
// static_cast, so 5.7e90, -1 or 2.5 in a config become undefined behaviour or a silent wrap (found by
// fuzz/config_fuzz.cpp). Here an integer field takes only a whole number its type can hold.
#include <nlohmann/json.hpp>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace tachi::common {

// v as T; integral T (not bool) must be a whole number in T's range. Throws std::invalid_argument
// (integers) or nlohmann::json::exception (other types, as json::get<T> does).
template <class T>
T json_value(const nlohmann::json& v) {
  if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) {
    const auto range = [] {
      return "a whole number from " + std::to_string(std::numeric_limits<T>::min()) + " to " +
             std::to_string(std::numeric_limits<T>::max());
    };
    if (v.is_number_unsigned()) {
      const auto u = v.get<std::uint64_t>();
      if (u > static_cast<std::uint64_t>(std::numeric_limits<T>::max())) throw std::invalid_argument("must be " + range());
      return static_cast<T>(u);
    }
    if (v.is_number_integer()) {
      const auto i = v.get<std::int64_t>();
      if constexpr (std::is_unsigned_v<T>) {
        if (i < 0) throw std::invalid_argument("must be " + range());
      } else {
        if (i < static_cast<std::int64_t>(std::numeric_limits<T>::min())) throw std::invalid_argument("must be " + range());
      }
      if (i > 0 && static_cast<std::uint64_t>(i) > static_cast<std::uint64_t>(std::numeric_limits<T>::max()))
        throw std::invalid_argument("must be " + range());
      return static_cast<T>(i);
    }
    if (v.is_number_float()) {
      // 3.0 is accepted as 3 (JSON writers differ); the bounds compare in long double, which holds both exactly
      // enough: max()+1 is a power of two.
      const double d = v.get<double>();
      const long double lo = static_cast<long double>(std::numeric_limits<T>::min());
      const long double hi_exclusive = static_cast<long double>(std::numeric_limits<T>::max()) + 1.0L;
      if (!std::isfinite(d) || std::floor(d) != d || d < lo || d >= hi_exclusive)
        throw std::invalid_argument("must be " + range() + " (got " + v.dump() + ")");
      return static_cast<T>(d);
    }
    throw std::invalid_argument("has the wrong type (" + std::string(v.type_name()) + "): must be " + range());
  } else {
    return v.get<T>();
  }
}

}  // namespace tachi::common
