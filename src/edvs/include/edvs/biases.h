#pragma once

// The bias registers of the DVS128 chip on the eDVS: their number and names in the order of the
// `!B<n>` commands (commands::setBias).

#include <optional>
#include <string_view>

namespace edvs {

/// Number of bias registers of the DVS128 chip on the eDVS and their names, index order.
inline constexpr int kNumBiases = 12;
const char* biasName(int index);
/// Index of a bias by its name (case-insensitive, e.g. "cas", "diffOn"); std::nullopt if unknown.
std::optional<int> biasIndex(std::string_view name);

}  // namespace edvs
