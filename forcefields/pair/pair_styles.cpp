#include "pair/pair_style.hpp"

namespace deli {

// The registrations, each defined in its style's own file (an explicit list: the linker
// drops unreferenced objects of a static library).
const PairStyle& lj_cut_pair_style();
const PairStyle& wca_pair_style();

const std::vector<const PairStyle*>& pair_styles() {
  static const std::vector<const PairStyle*> styles{&lj_cut_pair_style(), &wca_pair_style()};
  return styles;
}

const PairStyle* find_pair_style(const std::string& name) {
  for (const PairStyle* style : pair_styles()) {
    if (style->name == name) return style;
  }
  return nullptr;
}

}  // namespace deli
