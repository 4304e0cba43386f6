// Force-included into every translation unit that links spdlog (top-level CMakeLists.txt), never
// included by hand. spdlog's logger::log_ calls fmt::detail::vformat_to<char>, and fmt 9's headers
// declare no explicit instantiation of it, so every translation unit that logs compiled fmt's whole
// formatting engine again (integers, floats with dragonbox and dragon4, padding, escaping: ~2.5 s of
// -O3 code generation a translation unit, a third of the cold demo build's spdlog cost). The shared
// libfmt (Debian's libfmt9, the same 9.x as the headers: FMT_SHARED) exports that instantiation, so
// declaring it extern here makes every logging call use the library's copy instead.
#pragma once

#include <fmt/core.h>

#if defined(FMT_SHARED) && !defined(FMT_HEADER_ONLY) && FMT_VERSION >= 90000 && FMT_VERSION < 100000
FMT_BEGIN_NAMESPACE
namespace detail {
extern template FMT_API void vformat_to<char>(buffer<char>&, basic_string_view<char>,
                                              basic_format_args<FMT_BUFFER_CONTEXT(type_identity_t<char>)>, locale_ref);
}  // namespace detail
FMT_END_NAMESPACE
#endif
