#pragma once

// ASCII lower case for the case-insensitive names of formats, firmware, sync modes and biases.

#include <algorithm>
#include <cctype>
#include <string>
#include <string_view>

namespace edvs::detail {

inline std::string lower(std::string_view text) {
  std::string out(text);
  std::transform(out.begin(), out.end(), out.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

}  // namespace edvs::detail
