#pragma once
// Shared by the PNG and OpenEXR codecs (not installed).

#include <cstddef>
#include <string>

#include "qs/image/image_file.h"

namespace qs::image::detail {

inline constexpr std::size_t kMessageSize = 256;  ///< a codec's own message, classified and dropped

/// "<where>: <what> (<why>; expected <expected>)".
inline std::string message(const std::string& where, const std::string& what, const std::string& why,
                           const Expected& expected) {
  return where + ": " + what + " (" + why + "; expected " + expected.what + ")";
}

}  // namespace qs::image::detail
