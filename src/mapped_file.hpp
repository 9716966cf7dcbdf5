#pragma once
// A read-only view of a whole regular file (log_reader, series_file).

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <sys/stat.h>
#include <unistd.h>
#include <algorithm>

#include <string>
#include <string_view>

namespace accelcal::internal {

// A read-only view of a whole regular file, mapped and pre-faulted in one call: cheaper than
// copying it into a buffer page by page (ReadFileToString remains the fallback).
class MappedFile {
 public:
  explicit MappedFile(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return;
    struct stat st;
    if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_size > 0) {
      size_ = static_cast<std::size_t>(st.st_size);
      // No MAP_POPULATE: it reads the whole file before the parser sees its first line, so a
      // 10 GB file that fails on line 1 took 35 s and 10 GB of memory. Sequential advice keeps
      // the kernel reading ahead of the parser instead.
      void* p = ::mmap(nullptr, size_, PROT_READ, MAP_PRIVATE, fd, 0);
      if (p != MAP_FAILED) {
        data_ = static_cast<const char*>(p);
        ::madvise(p, size_, MADV_SEQUENTIAL);
      }
    }
    ::close(fd);
  }
  ~MappedFile() {
    if (data_ != nullptr) ::munmap(const_cast<char*>(data_), size_);
  }
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  bool ok() const { return data_ != nullptr; }
  /// Gives the pages wholly before `offset` back to the kernel: a parser that has consumed them
  /// keeps a constant footprint of the file instead of all of it (the mapping is read-only and
  /// private, so they would be read again from the file if touched).
  void ReleaseBefore(std::size_t offset) const {
    const std::size_t page = static_cast<std::size_t>(::sysconf(_SC_PAGESIZE));
    const std::size_t end = std::min(offset, size_) / page * page;
    if (data_ != nullptr && end > 0) ::madvise(const_cast<char*>(data_), end, MADV_DONTNEED);
  }
  std::string_view text() const { return {data_, size_}; }

 private:
  const char* data_ = nullptr;
  std::size_t size_ = 0;
};

}  // namespace accelcal::internal
