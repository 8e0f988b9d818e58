// libFuzzer target: device URI parsing must either succeed or throw std::invalid_argument.
#include <cstdint>
#include <stdexcept>
#include <string>

#include "edvs/device.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string uri(reinterpret_cast<const char*>(data), size);
  try {
    edvs::parseDeviceUri(uri);
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
