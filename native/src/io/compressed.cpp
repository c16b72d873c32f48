#include "io/compressed.h"

#include <algorithm>
#include <cstring>
#include <limits>

#include <zlib.h>

#include "particlemesh/core/error.h"

namespace PM_NAMESPACE::detail {

namespace {
constexpr size_t kChunk = size_t(1) << 16;

std::string zlib_message(const z_stream& s, int code) {
  if (s.msg) return s.msg;
  switch (code) {
    case Z_DATA_ERROR: return "invalid data";
    case Z_MEM_ERROR: return "out of memory";
    case Z_BUF_ERROR: return "the data ends too early";
    default: return "zlib error " + std::to_string(code);
  }
}
}  // namespace

struct GzipStream::Z {
  z_stream s{};
};

GzipStream::GzipStream(FileReader& file) : file_(file) {
  const std::string_view head = file_.look_ahead(2);
  zipped_ = head.size() == 2 && static_cast<unsigned char>(head[0]) == 0x1f && static_cast<unsigned char>(head[1]) == 0x8b;
  if (!zipped_) return;
  z_ = new Z;
  // 16 + 15: a gzip wrapper and the largest window.
  if (inflateInit2(&z_->s, 16 + MAX_WBITS) != Z_OK) {
    delete z_;
    z_ = nullptr;
    throw Error(Status::OutOfMemory, "'" + file_.path() + "': cannot start the gzip decompressor");
  }
  in_.resize(kChunk);
  out_.resize(kChunk);
}

GzipStream::~GzipStream() {
  if (z_) {
    inflateEnd(&z_->s);
    delete z_;
  }
}

bool GzipStream::refill() {
  consumed_ += end_;
  pos_ = end_ = 0;
  if (finished_) return false;
  z_stream& s = z_->s;
  while (end_ == 0) {
    if (s.avail_in == 0) {
      // Whatever the file has left (a FIFO gives what it has).
      const size_t got = file_.read_some(in_.data(), in_.size());
      if (got == 0) {
        // The file ended inside a gzip member (after a complete one, finished_ is set below).
        throw Error(Status::FormatError, "'" + file_.path() + "': truncated: the gzip data ends before its end marker (at byte " +
                                             std::to_string(file_.offset()) + " of the file)");
      }
      s.next_in = in_.data();
      s.avail_in = uInt(got);
    }
    s.next_out = out_.data();
    s.avail_out = uInt(out_.size());
    const int r = inflate(&s, Z_NO_FLUSH);
    end_ = out_.size() - s.avail_out;
    if (r == Z_STREAM_END) {
      // Another member may follow (concatenated gzip files are one stream).
      if (s.avail_in == 0 && file_.peek() < 0) {
        finished_ = true;
        return end_ > 0;
      }
      if (inflateReset(&s) != Z_OK)
        throw Error(Status::FormatError, "'" + file_.path() + "': the gzip data is corrupt (cannot read the next member)");
      continue;
    }
    if (r != Z_OK && r != Z_BUF_ERROR)
      throw Error(Status::FormatError, "'" + file_.path() + "': the gzip data is corrupt (" + zlib_message(s, r) +
                                           ") near byte " + std::to_string(file_.offset()) + " of the file");
  }
  return true;
}

bool GzipStream::read(void* out, size_t n) {
  if (!zipped_) return file_.read(out, n);
  auto* o = static_cast<unsigned char*>(out);
  while (n > 0) {
    if (pos_ == end_ && !refill()) return false;
    const size_t k = std::min(n, end_ - pos_);
    std::memcpy(o, out_.data() + pos_, k);
    pos_ += k;
    o += k;
    n -= k;
  }
  return true;
}

bool GzipStream::skip(uint64_t n) {
  if (!zipped_) return file_.skip(n);
  while (n > 0) {
    if (pos_ == end_ && !refill()) return false;
    const size_t k = size_t(std::min<uint64_t>(n, end_ - pos_));
    pos_ += k;
    n -= k;
  }
  return true;
}

bool GzipStream::at_end() {
  if (!zipped_) return file_.peek() < 0;
  return pos_ == end_ && !refill();
}

void inflate_block(const unsigned char* in, size_t in_size, unsigned char* out, size_t out_size,
                   const std::string& path, const std::string& what) {
  auto fail = [&](const std::string& problem) {
    throw Error(Status::FormatError, "'" + path + "': " + what + ": " + problem);
  };
  // zlib counts in 32 bits; VTK writes blocks of 32 KiB (vtkDataCompressor's default).
  constexpr size_t kMax = std::numeric_limits<uInt>::max();
  if (in_size > kMax || out_size > kMax) fail("a compressed block of over 4 GiB (VTK writes 32 KiB blocks)");
  z_stream s{};
  if (inflateInit(&s) != Z_OK) throw Error(Status::OutOfMemory, "'" + path + "': cannot start the zlib decompressor");
  s.next_in = const_cast<unsigned char*>(in);
  s.avail_in = uInt(in_size);
  s.next_out = out;
  s.avail_out = uInt(out_size);
  const int r = inflate(&s, Z_FINISH);
  const size_t made = out_size - s.avail_out;
  const std::string message = r == Z_DATA_ERROR || r == Z_MEM_ERROR || r == Z_STREAM_ERROR ? zlib_message(s, r) : "";
  inflateEnd(&s);
  if (r == Z_STREAM_END) {
    if (made != out_size)
      fail("a zlib block holds fewer bytes than its header says (" + std::to_string(made) + " of " +
           std::to_string(out_size) + ")");
    return;
  }
  if (r == Z_BUF_ERROR || r == Z_OK) {
    if (made == out_size) fail("a zlib block holds more bytes than its header says (" + std::to_string(out_size) + ")");
    fail("truncated zlib block (its data ends before its end marker)");
  }
  fail("the zlib data is corrupt (" + message + ")");
}

}  // namespace particlemesh::detail
