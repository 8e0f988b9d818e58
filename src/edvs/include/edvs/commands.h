#pragma once

// The ASCII command lines of the eDVS4337 (reset, streaming, event format, timestamp
// synchronisation, biases) and the banner it prints after reset.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "edvs/event_format.h"

namespace edvs {

/// Master/slave timestamp synchronisation of two sensors wired together: the master drives
/// the slave's timestamp clock, so both report the same device time.
enum class SyncMode { kNone, kMaster, kSlave };
const char* toString(SyncMode mode);
std::optional<SyncMode> parseSyncMode(std::string_view name);

/// Builders for the ASCII command lines. Every command ends in '\n'; send each in its own write.
namespace commands {
std::string reset();           ///< "R\n": reset; the device prints a banner
std::string echoOff();         ///< "!U0\n"
std::string startStreaming();  ///< "E+\n"
std::string stopStreaming();   ///< "E-\n"
std::string eventFormat(EventFormat format, Firmware firmware);  ///< "!E<n>\n"
std::string timestampReset();                                    ///< "!ET0\n"
std::string masterRun();   ///< "!ETM+\n": master starts its clock and the slave's
std::string masterStop();  ///< "!ETM0\n": master armed, clock stopped
std::string slave();       ///< "!ETS\n": take the timestamp clock from the master
std::string help();        ///< "??\n"
/// "!B<index>=<value>\n": set one bias register. Throws std::invalid_argument for index outside
/// 0..11 or a negative value or one above 2^24-1 (the bias generator's 24-bit range).
std::string setBias(int index, std::int64_t value);
std::string flushBiases();  ///< "!BF\n": send the bias registers to the chip
}  // namespace commands

/// True if `text` contains one of the banners an eDVS prints after reset
/// ("EDVS-4337" or "meDVS128").
bool containsBanner(std::string_view text);

}  // namespace edvs
