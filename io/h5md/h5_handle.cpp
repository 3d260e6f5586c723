#include "h5md/h5_handle.hpp"

namespace deli {

void prepare_hdf5() {
  static const bool prepared = [] {
    H5dont_atexit();  // fails harmlessly when the library was already in use
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    return true;
  }();
  (void)prepared;
}

}  // namespace deli
