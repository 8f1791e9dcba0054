// Copies 4- and 8-byte elements (float, uint32, double) between host order and the wire's
// little-endian bytes.
#pragma once

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>

namespace shadow::convert {

template <class T>
void host_to_le(const T* src, size_t count, char* dst) {
  static_assert(sizeof(T) == 4 || sizeof(T) == 8);
  if constexpr (std::endian::native == std::endian::little) {
    std::memcpy(dst, src, count * sizeof(T));
  } else if constexpr (sizeof(T) == 8) {
    for (size_t i = 0; i < count; ++i) {
      uint64_t u;
      std::memcpy(&u, src + i, 8);
      u = __builtin_bswap64(u);
      std::memcpy(dst + 8 * i, &u, 8);
    }
  } else {
    for (size_t i = 0; i < count; ++i) {
      uint32_t u;
      std::memcpy(&u, src + i, 4);
      u = __builtin_bswap32(u);
      std::memcpy(dst + 4 * i, &u, 4);
    }
  }
}

template <class T>
void le_to_host(const char* src, size_t count, T* dst) {
  static_assert(sizeof(T) == 4);
  if constexpr (std::endian::native == std::endian::little) {
    std::memcpy(dst, src, count * 4);
  } else {
    for (size_t i = 0; i < count; ++i) {
      uint32_t u;
      std::memcpy(&u, src + 4 * i, 4);
      u = __builtin_bswap32(u);
      std::memcpy(dst + i, &u, 4);
    }
  }
}

}  // namespace shadow::convert
