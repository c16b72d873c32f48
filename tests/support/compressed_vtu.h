// A .vtu of points whose Float32 positions are one raw appended array compressed as VTK's
// compressors write it (vtkDataCompressor's header: block count, block size, last block's
// size, each block's compressed size; UInt32 words), with zlib, LZ4 or LZMA (.xz), in blocks
// of `block_size` bytes. For the readers' tests and the fuzzer's seeds; link liblz4 and
// liblzma (and zlib).
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include <lz4.h>
#include <lzma.h>
#include <zlib.h>

namespace particlemesh::test {

enum class VtuCodec { Zlib, Lz4, Xz };

inline std::string compress_block(VtuCodec codec, const std::string& raw) {
  std::string out;
  switch (codec) {
    case VtuCodec::Zlib: {
      uLongf size = compressBound(uLong(raw.size()));
      out.resize(size);
      if (compress(reinterpret_cast<Bytef*>(out.data()), &size, reinterpret_cast<const Bytef*>(raw.data()),
                   uLong(raw.size())) != Z_OK)
        throw std::runtime_error("zlib compress failed");
      out.resize(size);
      break;
    }
    case VtuCodec::Lz4: {
      out.resize(size_t(LZ4_compressBound(int(raw.size()))));
      const int size = LZ4_compress_default(raw.data(), out.data(), int(raw.size()), int(out.size()));
      if (size <= 0) throw std::runtime_error("LZ4 compress failed");
      out.resize(size_t(size));
      break;
    }
    case VtuCodec::Xz: {
      out.resize(lzma_stream_buffer_bound(raw.size()));
      size_t size = 0;
      if (lzma_easy_buffer_encode(6, LZMA_CHECK_CRC64, nullptr, reinterpret_cast<const uint8_t*>(raw.data()),
                                  raw.size(), reinterpret_cast<uint8_t*>(out.data()), &size, out.size()) != LZMA_OK)
        throw std::runtime_error("xz compress failed");
      out.resize(size);
      break;
    }
  }
  return out;
}

/// The compressed array (header + blocks) of `raw` in blocks of `block_size` bytes.
inline std::string compressed_array(VtuCodec codec, const std::string& raw, size_t block_size) {
  std::vector<std::string> blocks;
  for (size_t at = 0; at < raw.size(); at += block_size) blocks.push_back(compress_block(codec, raw.substr(at, block_size)));
  std::string out;
  auto word = [&](uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
  word(uint32_t(blocks.size()));
  word(uint32_t(block_size));
  word(uint32_t(raw.size() % block_size));
  for (const auto& b : blocks) word(uint32_t(b.size()));
  for (const auto& b : blocks) out += b;
  return out;
}

inline const char* compressor_name(VtuCodec codec) {
  switch (codec) {
    case VtuCodec::Zlib: return "vtkZLibDataCompressor";
    case VtuCodec::Lz4: return "vtkLZ4DataCompressor";
    case VtuCodec::Xz: return "vtkLZMADataCompressor";
  }
  return "";
}

/// The whole file; `array` replaces the compressed positions when not empty (to damage them).
inline std::string compressed_vtu(VtuCodec codec, const std::vector<float>& xyz, size_t block_size,
                                  const std::string& array = "") {
  const std::string raw(reinterpret_cast<const char*>(xyz.data()), xyz.size() * sizeof(float));
  const size_t n = xyz.size() / 3;
  return std::string("<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
                     "byte_order=\"LittleEndian\" header_type=\"UInt32\" compressor=\"") +
         compressor_name(codec) + "\">\n<UnstructuredGrid><Piece NumberOfPoints=\"" + std::to_string(n) +
         "\" NumberOfCells=\"0\"><Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" format=\"appended\" "
         "offset=\"0\"/></Points></Piece></UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_" +
         (array.empty() ? compressed_array(codec, raw, block_size) : array) + "\n</AppendedData>\n</VTKFile>\n";
}

}  // namespace particlemesh::test
