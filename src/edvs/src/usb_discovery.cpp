#include "edvs/usb_discovery.h"

#include <libusb-1.0/libusb.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <stdexcept>

namespace edvs {

namespace {

namespace fs = std::filesystem;

std::string readLine(const fs::path& p) {
  std::ifstream in(p);
  std::string s;
  std::getline(in, s);
  return s;
}

/// sysfs: /sys/bus/usb/devices/<bus>-<port...> holds busnum/devnum/serial; its interface
/// directories hold ttyUSB<n> entries for the serial bridge.
struct SysfsInfo {
  std::string serial;
  std::string tty;
};

std::optional<SysfsInfo> sysfsLookup(int bus, int address) {
  const fs::path root("/sys/bus/usb/devices");
  std::error_code ec;
  if (!fs::exists(root, ec)) return std::nullopt;
  for (const auto& dev : fs::directory_iterator(root, ec)) {
    const fs::path busnum = dev.path() / "busnum";
    if (!fs::exists(busnum, ec)) continue;
    if (readLine(busnum) != std::to_string(bus) ||
        readLine(dev.path() / "devnum") != std::to_string(address)) {
      continue;
    }
    SysfsInfo info;
    info.serial = readLine(dev.path() / "serial");
    for (const auto& sub : fs::recursive_directory_iterator(
             dev.path(), fs::directory_options::skip_permission_denied, ec)) {
      const std::string name = sub.path().filename().string();
      if (name.rfind("ttyUSB", 0) == 0 || name.rfind("ttyACM", 0) == 0) {
        info.tty = "/dev/" + name;
        break;
      }
    }
    return info;
  }
  return std::nullopt;
}

struct ContextDeleter {
  void operator()(libusb_context* c) const { libusb_exit(c); }
};

}  // namespace

std::vector<UsbSerialDevice> listUsbSerialDevices(std::uint16_t vendor_id) {
  libusb_context* raw = nullptr;
  const int rc = libusb_init(&raw);
  if (rc != 0) {
    throw std::runtime_error(std::string("libusb_init failed: ") + libusb_error_name(rc) +
                             " (no USB support in this environment?)");
  }
  std::unique_ptr<libusb_context, ContextDeleter> context(raw);
  libusb_device** list = nullptr;
  const ssize_t count = libusb_get_device_list(context.get(), &list);
  std::vector<UsbSerialDevice> found;
  for (ssize_t i = 0; i < count; ++i) {
    libusb_device* dev = list[i];
    libusb_device_descriptor desc{};
    if (libusb_get_device_descriptor(dev, &desc) != 0 || desc.idVendor != vendor_id) continue;
    UsbSerialDevice d;
    d.vendor_id = desc.idVendor;
    d.product_id = desc.idProduct;
    d.bus = libusb_get_bus_number(dev);
    d.address = libusb_get_device_address(dev);
    libusb_device_handle* handle = nullptr;
    if (libusb_open(dev, &handle) == 0) {
      unsigned char text[256];
      if (desc.iSerialNumber != 0 &&
          libusb_get_string_descriptor_ascii(handle, desc.iSerialNumber, text, sizeof(text)) > 0) {
        d.serial_number = reinterpret_cast<const char*>(text);
      }
      if (desc.iProduct != 0 &&
          libusb_get_string_descriptor_ascii(handle, desc.iProduct, text, sizeof(text)) > 0) {
        d.product = reinterpret_cast<const char*>(text);
      }
      libusb_close(handle);
    }
    if (const auto info = sysfsLookup(d.bus, d.address)) {
      if (d.serial_number.empty()) d.serial_number = info->serial;
      d.tty = info->tty;
    }
    found.push_back(d);
  }
  if (list) libusb_free_device_list(list, 1);
  return found;
}

std::string findTtyBySerialNumber(const std::string& serial_number) {
  const auto devices = listUsbSerialDevices(kFtdiVendorId);
  std::string seen;
  for (const auto& d : devices) {
    if (d.serial_number == serial_number) {
      if (d.tty.empty()) {
        throw std::runtime_error("FTDI bridge " + serial_number +
                                 " is connected but provides no tty (is the ftdi_sio driver "
                                 "loaded and the device not claimed by another program?)");
      }
      return d.tty;
    }
    seen +=
        (seen.empty() ? "" : ", ") + (d.serial_number.empty() ? "<unreadable>" : d.serial_number);
  }
  throw std::runtime_error("no FTDI bridge (USB vendor 0403) with serial number " + serial_number +
                           " is connected; connected: " + (seen.empty() ? "none" : seen));
}

}  // namespace edvs
