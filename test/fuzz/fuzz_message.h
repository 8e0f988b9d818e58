#pragma once
// Bytes -> ROS message as roscpp deserialises a received message, for the fuzz targets.
//
// ros::serialization resizes a vector to the length the bytes claim before it finds that the
// bytes are too short, so random bytes would make it allocate up to 4 G elements. roscpp never
// sees such a message (a TCPROS frame holds the whole message, and its length bounds every
// array), so each message is first read into the same type with an allocator that refuses
// anything larger than the input could hold; only bytes that pass are read into the real type.

#include <ros/serialization.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <stdexcept>

namespace fuzz {

/// Refuses allocations beyond kMaxBytes (fuzz inputs are a few KiB).
template <class T>
struct CappedAllocator {
  using value_type = T;
  static constexpr std::size_t kMaxBytes = std::size_t{1} << 24;
  template <class U>
  struct rebind {
    using other = CappedAllocator<U>;
  };
  CappedAllocator() = default;
  template <class U>
  CappedAllocator(const CappedAllocator<U>&) {}  // NOLINT: rebinding is implicit
  T* allocate(std::size_t n) {
    if (n > kMaxBytes / sizeof(T)) throw std::bad_alloc();
    return std::allocator<T>().allocate(n);
  }
  void deallocate(T* p, std::size_t n) { std::allocator<T>().deallocate(p, n); }
};
template <class T, class U>
bool operator==(const CappedAllocator<T>&, const CappedAllocator<U>&) {
  return true;
}
template <class T, class U>
bool operator!=(const CappedAllocator<T>&, const CappedAllocator<U>&) {
  return false;
}

/// Reads one message of type Msg<std::allocator<void>> from data[0, size); returns the bytes it
/// used, 0 when the bytes are no such message (too short, or arrays longer than the input).
template <template <class> class Msg>
std::size_t readMessage(const std::uint8_t* data, std::size_t size,
                        Msg<std::allocator<void>>& out) {
  namespace ser = ros::serialization;
  if (size == 0 || size > 0xFFFFFFFFu) return 0;
  auto* bytes = const_cast<std::uint8_t*>(data);  // IStream reads only
  try {
    Msg<CappedAllocator<void>> probe;
    ser::IStream check(bytes, static_cast<std::uint32_t>(size));
    ser::deserialize(check, probe);
    ser::IStream stream(bytes, static_cast<std::uint32_t>(size));
    ser::deserialize(stream, out);
    return static_cast<std::size_t>(stream.getData() - bytes);
  } catch (const ser::StreamOverrunException&) {
  } catch (const std::bad_alloc&) {
  } catch (const std::length_error&) {
  }
  return 0;
}

/// Serialised bytes of a message (for the seed corpus).
template <class M>
std::vector<std::uint8_t> toBytes(const M& msg) {
  namespace ser = ros::serialization;
  std::vector<std::uint8_t> bytes(ser::serializationLength(msg));
  ser::OStream stream(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
  ser::serialize(stream, msg);
  return bytes;
}

}  // namespace fuzz
