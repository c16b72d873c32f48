#include "io/compressed.h"

#include <algorithm>
#include <cstring>
#include <limits>
#include <new>

#include <blosc.h>
#include <lz4.h>
#include <lzma.h>
#include <zlib.h>

#include "io/scalar_types.h"
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

struct DecompressedStream::Z {
  z_stream s{};
};

DecompressedStream::DecompressedStream(FileReader& file) : file_(file) {
  const std::string_view head = file_.look_ahead(4);
  if (head == "scf1") {
    mode_ = Mode::Scf;
    unpack_scf();
    return;
  }
  if (!(head.size() >= 2 && static_cast<unsigned char>(head[0]) == 0x1f && static_cast<unsigned char>(head[1]) == 0x8b))
    return;
  mode_ = Mode::Gzip;
  z_ = new Z;
  // 16 + 15: a gzip wrapper and the largest window.
  if (inflateInit2(&z_->s, 16 + MAX_WBITS) != Z_OK) {
    delete z_;
    z_ = nullptr;
    throw Error(Status::OutOfMemory, "'" + file_.path() + "': cannot start the gzip decompressor");
  }
  in_.resize(kChunk);
  out_.resize(kChunk);
  data_ = out_.data();
}

DecompressedStream::~DecompressedStream() {
  if (z_) {
    inflateEnd(&z_->s);
    delete z_;
  }
}

namespace {
uint64_t be64(const unsigned char* b) {
  uint64_t v = 0;
  for (int k = 0; k < 8; ++k) v = v << 8 | b[k];
  return v;
}
}  // namespace

// SideFX's SCF, the ".sc" of Houdini's .bgeo.sc (written by hand: no Debian package reads it;
// the layout as the HDK's UT_SCFReader.h / UT_SCFCommon.h name its parts and independent
// readers of Houdini's files take them apart; integers big-endian):
//
//   "scf1", uint64 M, M bytes of metadata (not needed here)
//   the content as consecutive Blosc chunks, each self-describing (a 16-byte header with its
//     uncompressed and compressed sizes), all of one uncompressed size but the last
//   the seek index: uint64s (where each chunk but the last ends, the chunks' uncompressed
//     size, the last one's), for readers that seek; only its length is used here
//   uint64: the index's length in bytes, then "1fcs"
//
// The chunks must fill the space between the metadata and the index exactly, and each must
// decompress to the size its header gives: a file cut short, patched or padded is refused.
// The content is unpacked whole (a .bgeo.sc is read once, front to back, like the others).
void DecompressedStream::unpack_scf() {
  const std::string& path = file_.path();
  const auto fail = [&](const std::string& what) {
    throw Error(Status::FormatError, "'" + path + "': a damaged .sc file (Houdini's Blosc-compressed SCF): " + what);
  };
  const std::string raw = file_.read_rest();
  const auto* b = reinterpret_cast<const unsigned char*>(raw.data());
  const size_t n = raw.size();
  constexpr size_t kHead = 12, kTail = 12;  // "scf1" + metadata length; index length + "1fcs"
  if (n < kHead + kTail) fail("only " + std::to_string(n) + " bytes");
  if (std::memcmp(b + n - 4, "1fcs", 4) != 0) fail("truncated (it does not end with the SCF footer '1fcs')");
  const uint64_t meta = be64(b + 4), index = be64(b + n - kTail);
  if (meta > n - kHead - kTail) fail("its metadata length (" + std::to_string(meta) + ") runs past its end");
  const size_t first = kHead + size_t(meta);
  if (index > n - kTail - first || index % 8 != 0)
    fail("its seek index length (" + std::to_string(index) + ") does not fit the file");
  const size_t last = n - kTail - size_t(index);  // where the chunks end
  // The largest expansion a Blosc chunk can give, with room: its compressors reach about
  // 250 (LZ4, BloscLZ), 930 (zlib) and 18 400 (Zstandard) to 1 on zeros. A header claiming
  // more is refused before anything is allocated.
  constexpr uint64_t kMaxRatio = 65536;
  struct Chunk {
    size_t at, bytes;
  };
  std::vector<Chunk> chunks;
  uint64_t total = 0;
  for (size_t at = first; at < last;) {
    size_t bytes = 0, cbytes = 0, blocksize = 0;
    if (last - at < 16) fail("the Blosc chunk at byte " + std::to_string(at) + " runs past the seek index");
    blosc_cbuffer_sizes(b + at, &bytes, &cbytes, &blocksize);  // the header's 16 bytes
    if (cbytes < 16 || cbytes > last - at)
      fail("the Blosc chunk at byte " + std::to_string(at) + " runs past the seek index");
    // Blosc's own check that decompressing the chunk is safe (its header against its length).
    if (blosc_cbuffer_validate(b + at, cbytes, &bytes) != 0)
      fail("the Blosc chunk at byte " + std::to_string(at) + " has a damaged header");
    if (bytes > cbytes * kMaxRatio)
      fail("the Blosc chunk at byte " + std::to_string(at) + " claims " + std::to_string(bytes) + " bytes from " +
           std::to_string(cbytes) + ", more than Blosc's compressors give");
    chunks.push_back({at, bytes});
    total += bytes;
    at += cbytes;
  }
  if (chunks.empty()) fail("it holds no compressed data");
  try {
    unpacked_.reset(new unsigned char[size_t(std::max<uint64_t>(total, 1))]);  // written below, not zeroed first
  } catch (const std::bad_alloc&) {
    throw Error(Status::OutOfMemory, "'" + path + "': no memory for its " + std::to_string(total) + " decompressed bytes");
  }
  size_t out = 0;
  for (const Chunk& c : chunks) {
    const int got = blosc_decompress_ctx(b + c.at, unpacked_.get() + out, c.bytes, 1);
    if (got < 0 || size_t(got) != c.bytes)
      fail("the Blosc chunk at byte " + std::to_string(c.at) + " does not decompress (corrupt data)");
    out += c.bytes;
  }
  data_ = unpacked_.get();
  pos_ = 0;
  end_ = size_t(total);
  finished_ = true;
}

bool DecompressedStream::refill() {
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

bool DecompressedStream::read(void* out, size_t n) {
  if (mode_ == Mode::Plain) return file_.read(out, n);
  auto* o = static_cast<unsigned char*>(out);
  while (n > 0) {
    if (pos_ == end_ && !refill()) return false;
    const size_t k = std::min(n, end_ - pos_);
    std::memcpy(o, data_ + pos_, k);
    pos_ += k;
    o += k;
    n -= k;
  }
  return true;
}

bool DecompressedStream::skip(uint64_t n) {
  if (mode_ == Mode::Plain) return file_.skip(n);
  while (n > 0) {
    if (pos_ == end_ && !refill()) return false;
    const size_t k = size_t(std::min<uint64_t>(n, end_ - pos_));
    pos_ += k;
    n -= k;
  }
  return true;
}

bool DecompressedStream::at_end() {
  if (mode_ == Mode::Plain) return file_.peek() < 0;
  return pos_ == end_ && !refill();
}

namespace {
/// Throws "'<path>': <what>: <problem>".
[[noreturn]] void block_error(const std::string& path, const std::string& what, const std::string& problem) {
  throw Error(Status::FormatError, "'" + path + "': " + what + ": " + problem);
}

void inflate_block(const unsigned char* in, size_t in_size, unsigned char* out, size_t out_size,
                   const std::string& path, const std::string& what) {
  const auto fail = [&](const std::string& problem) { block_error(path, what, problem); };
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

/// One raw LZ4 block, as vtkLZ4DataCompressor writes it (LZ4_compress_fast, no frame).
void lz4_block(const unsigned char* in, size_t in_size, unsigned char* out, size_t out_size, const std::string& path,
               const std::string& what) {
  const auto fail = [&](const std::string& problem) { block_error(path, what, problem); };
  constexpr size_t kMax = size_t(LZ4_MAX_INPUT_SIZE);
  if (in_size > kMax || out_size > kMax) fail("an LZ4 block of over 2 GB (VTK writes 32 KiB blocks)");
  const int made = LZ4_decompress_safe(reinterpret_cast<const char*>(in), reinterpret_cast<char*>(out), int(in_size),
                                       int(out_size));
  // LZ4's decoder tells a corrupt block from one that would overflow the output only by a
  // negative count; both are named.
  if (made < 0) fail("the LZ4 data is corrupt or holds more bytes than its header says (" + std::to_string(out_size) + ")");
  if (size_t(made) != out_size)
    fail("an LZ4 block holds fewer bytes than its header says (" + std::to_string(made) + " of " +
         std::to_string(out_size) + ")");
}

/// One .xz stream, as vtkLZMADataCompressor writes it (lzma_easy_buffer_encode).
void xz_block(const unsigned char* in, size_t in_size, unsigned char* out, size_t out_size, const std::string& path,
              const std::string& what) {
  // The decoder's memory is bounded: preset 9's 64 MiB dictionary needs 65 MiB; a stream
  // claiming a larger one is refused rather than allocated.
  uint64_t memlimit = uint64_t(128) << 20;
  size_t in_pos = 0, out_pos = 0;
  const lzma_ret r = lzma_stream_buffer_decode(&memlimit, 0, nullptr, in, &in_pos, in_size, out, &out_pos, out_size);
  if (r == LZMA_OK && out_pos == out_size) return;
  if (r == LZMA_MEM_ERROR) throw Error(Status::OutOfMemory, "'" + path + "': " + what + ": out of memory in the xz decoder");
  std::string problem;
  switch (r) {
    case LZMA_OK:
      problem = "an xz block holds fewer bytes than its header says (" + std::to_string(out_pos) + " of " +
                std::to_string(out_size) + ")";
      break;
    case LZMA_BUF_ERROR:
      problem = out_pos == out_size
                    ? "an xz block holds more bytes than its header says (" + std::to_string(out_size) + ")"
                    : "truncated xz block (its data ends before the end of its stream)";
      break;
    case LZMA_FORMAT_ERROR: problem = "the xz data is corrupt (it does not start with the .xz magic bytes)"; break;
    case LZMA_DATA_ERROR: problem = "the xz data is corrupt (it does not decode, or fails its own check)"; break;
    case LZMA_OPTIONS_ERROR: problem = "the xz data uses options liblzma does not support"; break;
    case LZMA_MEMLIMIT_ERROR:
      problem = "the xz data asks for " + std::to_string(memlimit >> 20) + " MiB to decode, more than the 128 MiB allowed";
      break;
    default: problem = "the xz data is corrupt (liblzma error " + std::to_string(int(r)) + ")";
  }
  block_error(path, what, problem);
}
}  // namespace

uint64_t max_decompressed_size(BlockCodec codec, uint64_t in_size) {
  switch (codec) {
    case BlockCodec::Zlib: return saturating_mul(in_size, 1032) + 64;
    case BlockCodec::Lz4: return saturating_mul(in_size, 256) + 64;
    case BlockCodec::Xz: return saturating_mul(in_size, 16384) + 4096;
  }
  return 0;
}

void decompress_block(BlockCodec codec, const unsigned char* in, size_t in_size, unsigned char* out, size_t out_size,
                      const std::string& path, const std::string& what) {
  switch (codec) {
    case BlockCodec::Zlib: return inflate_block(in, in_size, out, out_size, path, what);
    case BlockCodec::Lz4: return lz4_block(in, in_size, out, out_size, path, what);
    case BlockCodec::Xz: return xz_block(in, in_size, out, out_size, path, what);
  }
}

}  // namespace particlemesh::detail
