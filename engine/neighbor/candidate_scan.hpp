#pragma once

#include <cstddef>
#include <cstdint>

namespace deli {

// The neighbour-list build's innermost loop: the candidates m in [first, last) of a run of
// cells (positions by slot as structures of arrays x, y, z), tested against one particle's
// position shifted by a periodic image (ox, oy, oz). Every candidate with
// (x_m - ox)^2 + (y_m - oy)^2 + (z_m - oz)^2 < within2 (summed in that order, NaN never
// within) is appended, in slot order, as its slot to slot_out and `code` to code_out from
// position `hits` on; returns the new hit count. The output arrays must have room for
// hits + (last - first) + kScanSlack entries: the vector form stores whole vectors past the
// last hit. Built for the build machine's CPU under DELI_NATIVE (AVX-512: the test by
// vector and the hits compressed in registers); the same hits in the same order either way.
inline constexpr std::size_t kScanSlack = 16;
std::size_t scan_candidates(const double* x, const double* y, const double* z, std::size_t first,
                            std::size_t last, double ox, double oy, double oz, double within2,
                            std::uint8_t code, std::int32_t* slot_out, std::uint8_t* code_out,
                            std::size_t hits);

}  // namespace deli
