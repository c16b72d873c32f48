// Houdini's .sc container (SideFX's SCF) around any bytes, as Houdini writes a .bgeo.sc: "scf1",
// the metadata's length (big-endian uint64) and the metadata, the content in Blosc chunks of
// `block` uncompressed bytes (the last one shorter), the seek index (where each chunk but the
// last ends, relative to the first; the chunks' size; the last one's size: big-endian uint64s),
// its length in bytes, "1fcs". For the readers' tests and the fuzzer's seeds; link libblosc.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include <blosc.h>

namespace particlemesh::test {

inline void append_be64(std::string& s, uint64_t v) {
  for (int shift = 56; shift >= 0; shift -= 8) s.push_back(char((v >> shift) & 0xff));
}

/// `content` in SCF, compressed by Blosc's `codec` ("blosclz", "lz4", "zlib", "zstd"...),
/// byte shuffle on 4-byte items and level 9 (Houdini's UT_SCF_BLOSC_COMPRESSION_LEVEL).
inline std::string scf_wrap(const std::string& content, size_t block = 65536, const char* codec = "lz4",
                            const std::string& metadata = "") {
  std::string out = "scf1";
  append_be64(out, metadata.size());
  out += metadata;
  const size_t first = out.size();
  std::vector<uint64_t> ends;
  for (size_t at = 0; at < content.size(); at += block) {
    const size_t n = std::min(block, content.size() - at);
    std::string chunk(n + BLOSC_MAX_OVERHEAD, '\0');
    const int got = blosc_compress_ctx(9, BLOSC_SHUFFLE, 4, n, content.data() + at, chunk.data(), chunk.size(), codec,
                                       0, 1);
    if (got <= 0) throw std::runtime_error(std::string("blosc_compress_ctx failed with ") + codec);
    out.append(chunk.data(), size_t(got));
    ends.push_back(out.size() - first);
  }
  ends.pop_back();  // the last chunk ends where the index begins
  std::string index;
  for (uint64_t e : ends) append_be64(index, e);
  append_be64(index, block);
  append_be64(index, content.size() - (content.empty() ? 0 : (content.size() - 1) / block * block));
  out += index;
  append_be64(out, index.size());
  return out + "1fcs";
}

}  // namespace particlemesh::test
