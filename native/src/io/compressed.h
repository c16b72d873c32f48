// Internal: compressed data inside particle files, through zlib, LZ4, liblzma (the libraries
// VTK's own compressors call) and Blosc (Houdini's); zlib is on every system Blender runs on,
// the add-on zip carries the others.
//
//  - DecompressedStream: a file that may be compressed, read front to back: the file's own
//    bytes, or the decompressed stream when it starts with gzip's magic bytes (1f 8b: several
//    concatenated gzip members too; Houdini's classic .bgeo usually is) or with "scf1"
//    (SideFX's seekable compressed format around Blosc-compressed blocks: Houdini's .bgeo.sc,
//    the File Cache node's default; through libblosc).
//  - decompress_block: one compressed block of a VTK XML array into exactly the bytes its
//    header promises: vtkZLibDataCompressor (a zlib stream), vtkLZ4DataCompressor (one raw
//    LZ4 block) or vtkLZMADataCompressor (an .xz stream).
//
// Errors are Error(FormatError) naming the file and what was wrong ("the gzip data is
// corrupt: invalid distance too far back"), never the libraries' codes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "io/file_reader.h"

namespace PM_NAMESPACE::detail {

class DecompressedStream {
 public:
  /// Reads from `file` (which must stay alive), decompressing when it starts with gzip's
  /// magic bytes; a file that starts with "scf1" is read and decompressed whole here.
  /// @throws Error(FormatError) naming the file: a malformed SCF container or Blosc block.
  explicit DecompressedStream(FileReader& file);
  ~DecompressedStream();
  DecompressedStream(const DecompressedStream&) = delete;
  DecompressedStream& operator=(const DecompressedStream&) = delete;

  bool compressed() const { return mode_ != Mode::Plain; }
  /// Exactly `n` bytes into `out`; false when the stream ends first.
  bool read(void* out, size_t n);
  /// Skip `n` bytes; false when the stream ends first.
  bool skip(uint64_t n);
  /// Whether the stream has no byte left.
  bool at_end();
  /// Bytes of the (decompressed) stream consumed so far (of the file itself when it is not
  /// compressed: those are read from it directly).
  uint64_t offset() const { return mode_ != Mode::Plain ? consumed_ + pos_ : file_.offset(); }

 private:
  enum class Mode { Plain, Gzip, Scf };
  bool refill();
  void unpack_scf();

  FileReader& file_;
  Mode mode_ = Mode::Plain;
  struct Z;
  Z* z_ = nullptr;
  std::vector<unsigned char> in_, out_;
  std::unique_ptr<unsigned char[]> unpacked_;  ///< an SCF file's whole content
  const unsigned char* data_ = nullptr;         ///< out_'s or unpacked_'s bytes
  size_t pos_ = 0, end_ = 0;
  uint64_t consumed_ = 0;
  bool finished_ = false;
};

/// The block compressions of VTK's XML files, by their `compressor` attribute.
enum class BlockCodec { Zlib, Lz4, Xz };

/// The most bytes `in_size` compressed bytes can give, with some slack: deflate gives at most
/// 1032 to 1, LZ4 at most 255 to 1 (a byte of match length per 255), .xz at most about 7000
/// to 1 (Python's lzma, preset 9, on zeros: 248 for 32 KiB, 6827 for 128 MiB; bound 16384).
/// A block header claiming more is refused before anything is allocated.
uint64_t max_decompressed_size(BlockCodec codec, uint64_t in_size);

/// Decompress the block `in[0..in_size)` into exactly `out_size` bytes at `out`.
/// @throws Error(FormatError) "'<path>': <what>: the zlib data is corrupt (...)" (LZ4, xz
///         alike) or the block holds more or fewer bytes than `out_size`.
void decompress_block(BlockCodec codec, const unsigned char* in, size_t in_size, unsigned char* out, size_t out_size,
                      const std::string& path, const std::string& what);

}  // namespace particlemesh::detail
