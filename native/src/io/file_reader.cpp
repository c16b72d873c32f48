#include "io/file_reader.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "particlemesh/core/error.h"

namespace PM_NAMESPACE::detail {

namespace {
constexpr size_t kBuffer = size_t(1) << 16;
}

FileReader::FileReader(const std::string& path) : path_(path) {
  if (path.empty()) throw Error(Status::IoError, "no input file named (empty path)");
  do fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NOCTTY);
  while (fd_ < 0 && errno == EINTR);
  if (fd_ < 0) {
    const int e = errno;
    if (e == ENOENT) throw Error(Status::IoError, "'" + path + "': no such file");
    throw Error(Status::IoError, "'" + path + "': cannot open for reading: " + std::strerror(e));
  }
  struct stat st {};
  if (::fstat(fd_, &st) == 0) {
    if (S_ISDIR(st.st_mode)) {
      ::close(fd_);
      fd_ = -1;
      throw Error(Status::IoError, "'" + path + "' is a folder, not a file");
    }
    if (S_ISREG(st.st_mode)) size_ = int64_t(st.st_size);
  }
  buf_.resize(kBuffer);
}

FileReader::~FileReader() {
  if (fd_ >= 0) ::close(fd_);
}

bool FileReader::refill() {
  if (eof_) return false;
  consumed_ += end_;
  pos_ = end_ = 0;
  while (true) {
    const ssize_t got = ::read(fd_, buf_.data(), buf_.size());
    if (got > 0) {
      end_ = size_t(got);
      return true;
    }
    if (got == 0) {
      eof_ = true;
      return false;
    }
    if (errno == EINTR) continue;
    const int e = errno;
    throw Error(Status::IoError, "'" + path_ + "': read error: " + std::strerror(e));
  }
}

std::string_view FileReader::look_ahead(size_t n) {
  n = std::min<size_t>(n, 4096);
  while (end_ - pos_ < n && !eof_) {
    // Move what is left to the front and read more behind it.
    std::memmove(buf_.data(), buf_.data() + pos_, end_ - pos_);
    consumed_ += pos_;
    end_ -= pos_;
    pos_ = 0;
    const ssize_t got = ::read(fd_, buf_.data() + end_, buf_.size() - end_);
    if (got > 0) {
      end_ += size_t(got);
    } else if (got == 0) {
      eof_ = true;
    } else if (errno != EINTR) {
      const int e = errno;
      throw Error(Status::IoError, "'" + path_ + "': read error: " + std::strerror(e));
    }
  }
  return std::string_view(buf_.data() + pos_, std::min(n, end_ - pos_));
}

bool FileReader::read(void* out, size_t n) {
  auto* o = static_cast<char*>(out);
  while (n > 0) {
    if (pos_ == end_ && !refill()) return false;
    const size_t k = std::min(n, end_ - pos_);
    std::memcpy(o, buf_.data() + pos_, k);
    pos_ += k;
    o += k;
    n -= k;
  }
  return true;
}

size_t FileReader::read_some(void* out, size_t n) {
  if (pos_ == end_ && !refill()) return 0;
  const size_t k = std::min(n, end_ - pos_);
  std::memcpy(out, buf_.data() + pos_, k);
  pos_ += k;
  return k;
}

std::string FileReader::read_rest() {
  std::string out;
  if (size_ > 0 && uint64_t(size_) > offset()) out.reserve(size_t(uint64_t(size_) - offset()));
  char chunk[1 << 16];
  while (const size_t k = read_some(chunk, sizeof chunk)) out.append(chunk, k);
  return out;
}

bool FileReader::skip(uint64_t n) {
  while (n > 0) {
    if (pos_ == end_) {
      // A regular file: seek over whole buffers instead of reading them.
      if (size_ >= 0 && n > buf_.size()) {
        const uint64_t here = offset();
        if (here + n > uint64_t(size_)) return false;
        if (::lseek(fd_, off_t(here + n), SEEK_SET) >= 0) {
          consumed_ = here + n;
          pos_ = end_ = 0;
          return true;
        }
      }
      if (!refill()) return false;
    }
    const uint64_t k = std::min<uint64_t>(n, end_ - pos_);
    pos_ += size_t(k);
    n -= k;
  }
  return true;
}

bool FileReader::line(std::string_view& out, size_t max_length) {
  line_.clear();
  bool any = false;
  while (true) {
    if (pos_ == end_ && !refill()) {
      if (!any) return false;
      break;  // the last line, without a newline
    }
    any = true;
    const char* b = buf_.data() + pos_;
    const void* nl = std::memchr(b, '\n', end_ - pos_);
    const size_t len = nl ? size_t(static_cast<const char*>(nl) - b) : end_ - pos_;
    if (line_.size() + len > max_length)
      throw Error(Status::FormatError, "'" + path_ + "': line " + std::to_string(line_number_ + 1) +
                                           " is longer than " + std::to_string(max_length) +
                                           " bytes: not a text file of this kind");
    if (nl && line_.empty()) {
      // The whole line is in the buffer: no copy.
      out = std::string_view(b, len);
      pos_ += len + 1;
      ++line_number_;
      if (!out.empty() && out.back() == '\r') out.remove_suffix(1);
      return true;
    }
    line_.append(b, len);
    pos_ += len + (nl ? 1 : 0);
    if (nl) break;
  }
  ++line_number_;
  out = line_;
  if (!out.empty() && out.back() == '\r') out.remove_suffix(1);
  return true;
}

namespace {
inline bool space(int c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v'; }
}  // namespace

bool FileReader::token(std::string& out, size_t max_length, bool* ended_line) {
  out.clear();
  int c;
  do {
    c = get();
    if (c < 0) return false;
  } while (space(c));
  while (c >= 0 && !space(c)) {
    if (out.size() == max_length)
      throw Error(Status::FormatError, "'" + path_ + "': a value longer than " + std::to_string(max_length) +
                                           " bytes ('" + out.substr(0, 20) + "...') at byte " +
                                           std::to_string(offset()));
    out.push_back(char(c));
    c = get();
  }
  if (ended_line) {
    // Spaces and tabs up to the end of the line still count as the end of the line.
    while (c == ' ' || c == '\t' || c == '\r') c = get();
    *ended_line = c < 0 || c == '\n';
    if (!*ended_line) --pos_;  // put back the next token's first byte (get() just returned it from the buffer)
  }
  return true;
}

void FileReader::skip_line() {
  int c;
  do c = get();
  while (c >= 0 && c != '\n');
}

bool FileReader::only_whitespace_left() {
  int c;
  while ((c = get()) >= 0)
    if (!space(c) && c != 0) return false;
  return true;
}

}  // namespace particlemesh::detail
