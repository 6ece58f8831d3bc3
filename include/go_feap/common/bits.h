// One bit per voxel in a vector of 64-bit words (voxel l: bit l mod 64 of word l / 64).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace go_feap::common {

inline bool testBit(const std::vector<std::uint64_t>& bits, std::size_t l) { return (bits[l >> 6] >> (l & 63)) & 1u; }
inline void setBit(std::vector<std::uint64_t>& bits, std::size_t l) { bits[l >> 6] |= std::uint64_t{1} << (l & 63); }
inline void clearBit(std::vector<std::uint64_t>& bits, std::size_t l) { bits[l >> 6] &= ~(std::uint64_t{1} << (l & 63)); }

}  // namespace go_feap::common
