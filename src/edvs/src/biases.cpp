#include "edvs/biases.h"
#include <array>
#include <stdexcept>
#include <string>

#include "lowercase.h"

namespace edvs {

using detail::lower;

namespace {

// DVS128 bias registers in the order of the eDVS !B<n> commands.
constexpr std::array<const char*, kNumBiases> kBiasNames = {"cas",     "injGnd", "reqPd", "puX",
                                                            "diffOff", "req",    "refr",  "puY",
                                                            "diffOn",  "diff",   "foll",  "pr"};

}  // namespace

const char* biasName(int index) {
  if (index < 0 || index >= kNumBiases) {
    throw std::invalid_argument("bias index " + std::to_string(index) + " out of range");
  }
  return kBiasNames[static_cast<std::size_t>(index)];
}

std::optional<int> biasIndex(std::string_view name) {
  const std::string n = lower(name);
  for (int i = 0; i < kNumBiases; ++i) {
    if (lower(kBiasNames[static_cast<std::size_t>(i)]) == n) return i;
  }
  return std::nullopt;
}

}  // namespace edvs
