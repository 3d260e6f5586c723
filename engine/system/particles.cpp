#include "system/particles.hpp"

namespace deli {

void Particles::resize(std::size_t n) {
  position.resize(n);
  velocity.resize(n);
  mass.resize(n, 1.0);
  radius.resize(n, 0.5);
  type.resize(n, 0);
  id.resize(n, 0);
  molecule.resize(n, 0);
  image.resize(n, {0, 0, 0});
}

}  // namespace deli
