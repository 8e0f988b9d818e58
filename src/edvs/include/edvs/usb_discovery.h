#pragma once

// Discovery of eDVS sensors: FTDI USB-serial bridges (vendor 0x0403) through libusb, with their
// serial numbers and, where sysfs shows it, the tty device node each one provides. ROS-free.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace edvs {

inline constexpr std::uint16_t kFtdiVendorId = 0x0403;

struct UsbSerialDevice {
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
  int bus = 0;
  int address = 0;
  std::string serial_number;  ///< empty if it could not be read (permissions)
  std::string product;        ///< product string, if readable
  std::string tty;            ///< e.g. /dev/ttyUSB0; empty if not found in sysfs
};

/// Lists connected USB devices with the given vendor id. Serial numbers come from the device
/// descriptor (libusb, needs read access to the USB node) or, failing that, from sysfs.
/// Throws std::runtime_error if libusb cannot be initialised.
std::vector<UsbSerialDevice> listUsbSerialDevices(std::uint16_t vendor_id = kFtdiVendorId);

/// The tty node of the FTDI bridge with this serial number. Throws std::runtime_error naming
/// the serial numbers that are connected when none matches.
std::string findTtyBySerialNumber(const std::string& serial_number);

}  // namespace edvs
