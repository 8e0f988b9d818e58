// Lists FTDI USB-serial bridges (USB vendor 0403, the eDVS's bridge) with their serial numbers
// and tty nodes, for choosing a device by serial number: serial://?serial_number=<serial>.
#include <cstdio>
#include <exception>

#include "edvs/usb_discovery.h"

int main() {
  try {
    const auto devices = edvs::listUsbSerialDevices();
    if (devices.empty()) {
      std::printf("no FTDI USB-serial bridge (vendor 0403) connected\n");
      return 1;
    }
    std::printf("%-4s %-4s %-9s %-20s %-14s %s\n", "bus", "addr", "vid:pid", "serial", "tty",
                "product");
    for (const auto& d : devices) {
      std::printf("%-4d %-4d %04x:%04x %-20s %-14s %s\n", d.bus, d.address, d.vendor_id,
                  d.product_id, d.serial_number.empty() ? "<unreadable>" : d.serial_number.c_str(),
                  d.tty.empty() ? "-" : d.tty.c_str(), d.product.c_str());
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "edvs_list_devices: %s\n", e.what());
    return 2;
  }
}
