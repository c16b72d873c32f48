// Internal: a file read once, front to back, through one buffer.
//
// Every reader of particlemesh reads its file through this class exactly once: no header
// pass before a data pass, no second reader. It uses read(2), so FIFOs, devices and
// /dev/stdin are read like files; nothing is sized from what a header claims (a header's
// counts are only trusted as far as the bytes really there).
#pragma once

#include "particlemesh/core/config.h"

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace PM_NAMESPACE::detail {

class FileReader {
 public:
  /// Opens `path` for reading. @throws Error(IoError) naming the file: no such file, a
  /// folder, no permission.
  explicit FileReader(const std::string& path);
  ~FileReader();
  FileReader(const FileReader&) = delete;
  FileReader& operator=(const FileReader&) = delete;

  const std::string& path() const { return path_; }
  /// The file's size when it is a regular file (what a header's counts are checked against),
  /// else -1 (a FIFO or a device: its length is only known at its end).
  int64_t size() const { return size_; }
  /// Bytes consumed so far.
  uint64_t offset() const { return consumed_ + pos_; }

  /// The next byte (0..255), or -1 at the end of the file.
  int peek() {
    if (pos_ == end_ && !refill()) return -1;
    return static_cast<unsigned char>(buf_[pos_]);
  }
  int get() {
    if (pos_ == end_ && !refill()) return -1;
    return static_cast<unsigned char>(buf_[pos_++]);
  }
  /// The next `n` bytes (n <= 4096) without consuming them; fewer at the end of the file.
  std::string_view look_ahead(size_t n);
  /// Exactly `n` bytes into `out`; false when the file ends first.
  bool read(void* out, size_t n);
  /// Up to `n` bytes into `out`: what the buffer holds, or one read's worth; 0 only at the end
  /// of the file.
  size_t read_some(void* out, size_t n);
  /// Everything left in the file (for formats whose parts refer to each other by offset).
  std::string read_rest();
  /// Skip `n` bytes; false when the file ends first.
  bool skip(uint64_t n);

  /// The next line, without its '\n' and a '\r' before it; false at the end of the file.
  /// The view stays valid until the next call. A line longer than `max_length` bytes is a
  /// FormatError naming the file and the line (a file that never ends a line, such as
  /// /dev/zero, is refused after `max_length` bytes, not read into memory whole).
  bool line(std::string_view& out, size_t max_length);
  /// Number of the line last returned by line() (1-based).
  uint64_t line_number() const { return line_number_; }

  /// The next whitespace-separated token (spaces, tabs, CR, LF), at most `max_length`
  /// bytes (longer: FormatError); false at the end of the file. `ended_line` tells whether
  /// the token was followed by the end of its line (or of the file).
  bool token(std::string& out, size_t max_length, bool* ended_line = nullptr);
  /// Skip the rest of the current line (through its '\n').
  void skip_line();
  /// Whether only whitespace (and NUL padding) remains; consumes it.
  bool only_whitespace_left();

 private:
  bool refill();

  std::string path_;
  int fd_ = -1;
  int64_t size_ = -1;
  std::vector<char> buf_;
  size_t pos_ = 0, end_ = 0;
  uint64_t consumed_ = 0;  ///< bytes before buf_[0]
  bool eof_ = false;
  std::string line_;       ///< a line that spans buffer refills
  uint64_t line_number_ = 0;
};

}  // namespace particlemesh::detail
