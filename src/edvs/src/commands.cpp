#include "edvs/commands.h"
#include <stdexcept>

#include "edvs/biases.h"
#include "lowercase.h"

namespace edvs {

using detail::lower;

const char* toString(SyncMode mode) {
  switch (mode) {
    case SyncMode::kNone:
      return "none";
    case SyncMode::kMaster:
      return "master";
    case SyncMode::kSlave:
      return "slave";
  }
  return "?";
}

std::optional<SyncMode> parseSyncMode(std::string_view name) {
  const std::string n = lower(name);
  if (n == "none" || n == "off" || n.empty()) return SyncMode::kNone;
  if (n == "master") return SyncMode::kMaster;
  if (n == "slave") return SyncMode::kSlave;
  return std::nullopt;
}

namespace commands {
std::string reset() { return "R\n"; }
std::string echoOff() { return "!U0\n"; }
std::string startStreaming() { return "E+\n"; }
std::string stopStreaming() { return "E-\n"; }
std::string eventFormat(EventFormat format, Firmware firmware) {
  return "!E" + std::to_string(formatCommandNumber(format, firmware)) + "\n";
}
std::string timestampReset() { return "!ET0\n"; }
std::string masterRun() { return "!ETM+\n"; }
std::string masterStop() { return "!ETM0\n"; }
std::string slave() { return "!ETS\n"; }
std::string help() { return "??\n"; }
std::string setBias(int index, std::int64_t value) {
  if (index < 0 || index >= kNumBiases) {
    throw std::invalid_argument("bias index " + std::to_string(index) + " outside 0.." +
                                std::to_string(kNumBiases - 1));
  }
  if (value < 0 || value > 0xFFFFFF) {
    throw std::invalid_argument("bias value " + std::to_string(value) +
                                " outside the 24-bit range 0..16777215");
  }
  return "!B" + std::to_string(index) + "=" + std::to_string(value) + "\n";
}
std::string flushBiases() { return "!BF\n"; }
}  // namespace commands

bool containsBanner(std::string_view text) {
  return text.find("EDVS-4337") != std::string_view::npos ||
         text.find("meDVS128") != std::string_view::npos;
}

}  // namespace edvs
