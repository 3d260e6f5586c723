#pragma once

#include <cstddef>
#include <cstdint>

#include "core/vec3.hpp"
#include "thermostats/random_stream.hpp"

namespace deli {

// The first three normals of RandomStream(seed, start[k]) for k < count, into out[k]: the
// numbers three calls of RandomStream::normal() give, bit for bit. Where the build has
// AVX-512 (normal_triples_vectorised()), eight streams at a time (with AVX2, four): their first
// three Philox blocks by vector, the polar method's first two accepted pairs picked by mask and
// finished by vector (the logarithm polar_log, by vector under AVX2: the same values); a stream
// that accepts fewer than two of its first six pairs (0.2 % of them) is drawn by RandomStream.
void normal_triples(std::uint64_t seed, const PhiloxCounter* start, std::size_t count, Vec3* out);
bool normal_triples_vectorised();

// RandomStream's three calls, stream by stream: the reference normal_triples keeps.
void normal_triples_by_stream(std::uint64_t seed, const PhiloxCounter* start, std::size_t count,
                              Vec3* out);

}  // namespace deli
