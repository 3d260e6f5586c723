#pragma once

#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

// The readers take a path: the fuzz input becomes an anonymous in-memory file, named by
// /proc/self/fd, so no run touches the disk and parallel fuzzers never share a name.
// HDF5 does not open such a path (H5Fis_hdf5 says no), so the checkpoint target asks for a
// regular file in the temporary folder (`on_disk`), named uniquely and removed at exit.
class FuzzFile {
 public:
  explicit FuzzFile(bool on_disk = false) {
    if (on_disk) {
      const char* dir = std::getenv("TMPDIR");
      disk_path_ = std::string(dir ? dir : "/tmp") + "/deli-fuzz-XXXXXX";
      fd_ = mkstemp(disk_path_.data());
    } else {
      fd_ = memfd_create("deli-fuzz", 0);
    }
    if (fd_ < 0) std::abort();
  }
  ~FuzzFile() {
    close(fd_);
    if (!disk_path_.empty()) unlink(disk_path_.c_str());
  }
  FuzzFile(const FuzzFile&) = delete;
  FuzzFile& operator=(const FuzzFile&) = delete;

  // The file holds exactly `size` bytes of `data`; returns its path.
  std::string hold(const std::uint8_t* data, std::size_t size) {
    if (ftruncate(fd_, 0) != 0 || lseek(fd_, 0, SEEK_SET) != 0) std::abort();
    for (std::size_t done = 0; done < size;) {
      const ssize_t wrote = write(fd_, data + done, size - done);
      if (wrote <= 0) std::abort();
      done += static_cast<std::size_t>(wrote);
    }
    return disk_path_.empty() ? "/proc/self/fd/" + std::to_string(fd_) : disk_path_;
  }

 private:
  int fd_ = -1;
  std::string disk_path_;
};
