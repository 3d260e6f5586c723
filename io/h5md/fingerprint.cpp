#include "h5md/fingerprint.hpp"

namespace deli {

void Fnv1a::add(const void* data, std::size_t bytes) {
  const auto* byte = static_cast<const unsigned char*>(data);
  for (std::size_t k = 0; k < bytes; ++k) {
    hash_ ^= byte[k];
    hash_ *= 0x100000001b3ull;
  }
}

std::uint64_t fnv1a(const void* data, std::size_t bytes) {
  Fnv1a h;
  h.add(data, bytes);
  return h.value();
}

std::uint64_t system_fingerprint(const System& system, const std::string& model) {
  Fnv1a h;
  const Particles& p = system.particles;
  h.add_value(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    h.add_value(p.id[i]);
    h.add_value(p.type[i]);
    h.add_value(p.mass[i]);
    h.add_value(p.radius[i]);
  }
  h.add_value(system.topology.bonds.size());
  for (const Bond& b : system.topology.bonds) {
    h.add_value(b.i), h.add_value(b.j), h.add_value(b.type);
  }
  h.add_value(system.topology.angles.size());
  for (const Angle& a : system.topology.angles) {
    h.add_value(a.i), h.add_value(a.j), h.add_value(a.k), h.add_value(a.type);
  }
  // Only when there are some: the fingerprints of systems without dihedrals stay as they were.
  if (!system.topology.dihedrals.empty()) {
    h.add_value(system.topology.dihedrals.size());
    for (const Dihedral& d : system.topology.dihedrals) {
      h.add_value(d.i), h.add_value(d.j), h.add_value(d.k), h.add_value(d.l), h.add_value(d.type);
    }
  }
  for (int a = 0; a < 3; ++a) {
    h.add_value(system.box.lo()[a]);
    h.add_value(system.box.hi()[a]);
    h.add_value(system.box.periodic(a));
  }
  h.add_value(model.size());
  h.add(model.data(), model.size());
  return h.value();
}

}  // namespace deli
