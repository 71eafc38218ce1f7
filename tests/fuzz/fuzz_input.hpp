#pragma once
// What the libFuzzer targets share: the input read byte by byte, and the signal of a finding.

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>

namespace affine_orb::fuzz {

/// A broken property: abort, which libFuzzer reports as a finding and keeps the input of.
inline void require(bool condition) {
  if (!condition) std::abort();
}

/// Reads the input in order, then zeros.
class Bytes {
 public:
  Bytes(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  std::uint8_t next() { return position_ < size_ ? data_[position_++] : 0; }
  /// The next four bytes as the bits of a float (big-endian): NaN, infinities and huge values too.
  float raw_float() {
    std::uint32_t bits = 0;
    for (int i = 0; i < 4; ++i) bits = bits << 8 | next();
    float f = 0.0f;
    std::memcpy(&f, &bits, sizeof(f));
    return f;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t position_ = 0;
};

}  // namespace affine_orb::fuzz
