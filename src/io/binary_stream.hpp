#pragma once
// A binary input read forward in bounded memory (the native log readers: ulog.cpp, ...): an
// InputFile in blocks, with the bytes a record needs made contiguous, each byte's offset in the
// input known for messages, and every byte read optionally hashed (a calibration's provenance).
// Little-endian values are read from the bytes with core/little_endian.hpp.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

#include "accelcal/sha256.hpp"
#include "core/little_endian.hpp"
#include "io/input_file.hpp"

namespace accelcal::internal {

class BinaryStream {
 public:
  /// Reads from `file` (which must outlive this), after `already_read`: the bytes its caller read
  /// first (to tell what the file is), which are the input's first.
  BinaryStream(InputFile* file, std::string already_read);
  /// The bytes of an input already in memory, named `name` in messages.
  BinaryStream(std::string bytes, std::string name);
  /// The bytes of an input in memory that outlives this, read where they are (not copied).
  struct Borrowed {};
  BinaryStream(std::string_view bytes, std::string name, Borrowed);
  /// Every byte from the input's start also goes into `hash`; call before the first Need.
  void Fingerprint(Sha256* hash) {
    hash_ = hash;
    hash_->Update(base(), end_);  // the bytes read first
  }

  /// Makes the next `n` bytes contiguous at data(); false when the input ends first (then
  /// available() says how many there are).
  bool Need(std::size_t n);
  const unsigned char* data() const { return base() + begin_; }
  std::size_t available() const { return end_ - begin_; }
  /// Consumes `n` bytes (at most available()).
  void Skip(std::size_t n) {
    begin_ += n;
    offset_ += n;
  }
  /// The input offset of data()[0].
  std::uint64_t offset() const { return offset_; }
  /// Whether the rest of the input is zeros (space a logger reserved and never wrote): then it is
  /// consumed; else `*nonzero` is the offset of its first byte that is not (and what is before it
  /// consumed).
  bool ZerosToEnd(std::uint64_t* nonzero);
  /// The message a reader gives for a log that ends in zeros from `at` (ZerosToEnd).
  static std::string ZerosMessage(std::uint64_t at);
  /// Reads and hashes the rest of the input (so that a fingerprint covers every byte), dropping it.
  void Drain();
  /// Consumes the next `n` bytes without holding them (a record a reader does not need, however
  /// large); false when the input ends first (then all of it is consumed).
  bool SkipAhead(std::uint64_t n);
  const std::string& name() const { return name_; }
  /// The error every binary reader raises: InputError naming the input and byte `at`, the
  /// reason escaped (names from the log reach it: one line, every character visible).
  [[noreturn]] void Fail(std::uint64_t at, const std::string& why) const;

 private:
  void Fill(std::size_t n);

  InputFile* file_;  // nullptr: all the input is in the buffer
  std::string name_;
  Sha256* hash_ = nullptr;
  const unsigned char* base() const { return view_ != nullptr ? view_ : buffer_.data(); }

  std::vector<unsigned char> buffer_;
  std::string owned_;                    // an input in memory, owned
  const unsigned char* view_ = nullptr;  // an input in memory: its bytes
  std::size_t begin_ = 0, end_ = 0;
  std::uint64_t offset_ = 0;
  bool eof_ = false;
};

}  // namespace accelcal::internal
