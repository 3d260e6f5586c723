#pragma once

#include <hdf5.h>

#include <utility>

namespace deli {

// An HDF5 identifier closed exactly once. close() is where HDF5 writes what it cached, so
// writers call it and check the result; the destructor only closes what an error path left
// open.
class H5Handle {
 public:
  using Closer = herr_t (*)(hid_t);
  H5Handle() = default;
  H5Handle(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  H5Handle(H5Handle&& other) noexcept : id_(std::exchange(other.id_, -1)), closer_(other.closer_) {}
  H5Handle& operator=(H5Handle&& other) noexcept {
    if (this != &other) {
      close();
      id_ = std::exchange(other.id_, -1);
      closer_ = other.closer_;
    }
    return *this;
  }
  H5Handle(const H5Handle&) = delete;
  H5Handle& operator=(const H5Handle&) = delete;
  ~H5Handle() { close(); }

  hid_t get() const { return id_; }
  operator hid_t() const { return id_; }
  bool valid() const { return id_ >= 0; }
  // Closes now; negative when HDF5 failed (the identifier is given up either way).
  herr_t close() {
    if (id_ < 0) return 0;
    const herr_t status = closer_(id_);
    id_ = -1;
    return status;
  }

 private:
  hid_t id_ = -1;
  Closer closer_ = nullptr;
};

inline H5Handle h5_file(hid_t id) {
  return {id, H5Fclose};
}
inline H5Handle h5_group(hid_t id) {
  return {id, H5Gclose};
}
inline H5Handle h5_dataset(hid_t id) {
  return {id, H5Dclose};
}
inline H5Handle h5_space(hid_t id) {
  return {id, H5Sclose};
}
inline H5Handle h5_type(hid_t id) {
  return {id, H5Tclose};
}
inline H5Handle h5_attribute(hid_t id) {
  return {id, H5Aclose};
}
inline H5Handle h5_properties(hid_t id) {
  return {id, H5Pclose};
}

// Call before any other HDF5 function: errors come back as codes that deli reports (no
// HDF5 error stack on stderr), and HDF5's exit handler is not registered. deli closes
// every file itself; that handler closes again a file whose close failed (a full disk) and
// crashes (SIGSEGV in H5F__close_cb, HDF5 1.10).
void prepare_hdf5();

}  // namespace deli
