#pragma once
// Reading an input in blocks, with bounded memory whatever the input is (log_reader,
// series_file): a regular file is read up to the size it had when opened, and a file that shrinks
// while it is read (a logger rotating it with copytruncate) is an error, not a crash (it used to
// be mapped, and touching a page past the new end raised SIGBUS); anything else (a pipe, a
// device such as /dev/zero, standard input) is read up to a stated limit. TextBlocks hands the
// text on in blocks of whole lines, so a parser holds one block at a time, never the file.

#include <cstddef>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "accelcal/sha256.hpp"

namespace accelcal::internal {

class InputFile {
 public:
  /// Opens `path` ("-": standard input, named "<stdin>"). Throws InputError naming the path when
  /// it cannot be opened or is a directory.
  InputFile(const std::string& path, std::size_t max_stream_bytes);
  ~InputFile();
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;

  const std::string& name() const { return name_; }
  bool regular() const { return regular_; }
  /// A regular file's size when it was opened, less the offset it was opened at (standard input
  /// may have been read from); 0 for anything else.
  std::size_t size() const { return size_; }
  /// Reads up to `n` bytes into `out`; 0 at the end. Throws InputError when the read fails, when
  /// a regular file ends before the size it had when opened, or when more than
  /// `max_stream_bytes` come from anything else.
  std::size_t Read(char* out, std::size_t n);
  /// How many bytes Read has returned.
  std::size_t bytes_read() const { return done_; }
  /// Read until `n` bytes came or the input ended; how many came.
  std::size_t ReadFully(char* out, std::size_t n) {
    std::size_t done = 0;
    for (std::size_t got; done < n && (got = Read(out + done, n - done)) > 0;) done += got;
    return done;
  }
  /// A regular file whose size or modification time is not what it was when opened: how (for a
  /// message, "grew from 10 to 12 bytes"); nullopt when unchanged or not a regular file.
  std::optional<std::string> Changed() const;

 private:
  std::string name_;
  int fd_ = -1;
  bool owned_ = false;
  bool regular_ = false;
  std::size_t start_ = 0;  // a regular file's offset when opened (standard input may be past 0)
  long long mtime_s_ = 0, mtime_ns_ = 0;
  std::size_t size_ = 0;
  std::size_t done_ = 0;
  std::size_t max_stream_bytes_;
};

class BackgroundHash;

/// The text of an input in blocks of whole lines.
class TextBlocks {
 public:
  /// Blocks read from `file` (which must outlive this), after `already_read`: the bytes its
  /// caller read first (to tell what the file is).
  explicit TextBlocks(InputFile* file, std::string already_read = {});
  /// One block: the whole of `text` (which must outlive this).
  explicit TextBlocks(std::string_view text);
  /// Text made as it is read (a MAT file's matrix as rows): `source` writes up to `n` bytes to
  /// `out` and says how many, 0 at the end; `total` its size when known (else 0).
  using Source = std::function<std::size_t(char* out, std::size_t n)>;
  TextBlocks(Source source, std::size_t total);
  ~TextBlocks();
  TextBlocks(const TextBlocks&) = delete;
  TextBlocks& operator=(const TextBlocks&) = delete;

  /// Every byte of the input from now on (and `already_read`) also goes into `hash`, on a
  /// second thread while the blocks are parsed: the same digest as hashing them in order here,
  /// off the parse's path (1.9 ms of the 3.3 MB Xsens log). Call before the first Peek or Next;
  /// `hash` must outlive this. Read it only after Finish.
  void Fingerprint(Sha256* hash);
  /// Waits until every byte read so far is in the hash.
  void FinishFingerprint();

  /// The unconsumed text, at least `min_bytes` of it unless the input ends first, cut after its
  /// last whole line (unless the input ended); valid until the next call.
  std::string_view Peek(std::size_t min_bytes);
  /// Whether Peek's text reaches the end of the input.
  bool AtEnd() const { return eof_ && end_ - begin_ == peeked_; }
  /// The next block of whole lines (the rest of the input at its end), consumed; false when
  /// nothing is left. Valid until the next call.
  bool Next(std::string_view* block);
  /// Offset in the input of the last block's first byte.
  std::size_t block_offset() const { return block_offset_; }
  /// The input's size when known (a regular file or text in memory), else 0.
  std::size_t total() const { return total_; }
  char line_end() const { return eol_; }

 private:
  void Fill(std::size_t min_bytes);
  std::string_view WholeLines() const;

  InputFile* file_ = nullptr;
  Source source_;
  // The block buffer, not zero-filled (every byte used is read into it first), and with a hash
  // the other it alternates with (one is read while the other's block is hashed).
  std::unique_ptr<char[]> buffer_, spare_;
  std::size_t capacity_ = 0, spare_capacity_ = 0;
  const char* data_ = nullptr;  // buffer_.get(), or the text in memory
  std::size_t begin_ = 0, end_ = 0, peeked_ = 0;
  std::size_t base_ = 0;  // input offset of data_[0]
  std::size_t block_offset_ = 0;
  std::size_t total_ = 0;
  bool eof_ = false;
  bool started_ = false;
  char eol_ = '\n';
  std::unique_ptr<BackgroundHash> hash_;
};

}  // namespace accelcal::internal
