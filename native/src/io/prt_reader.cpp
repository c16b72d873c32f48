// Thinkbox Krakatoa's particle files, .prt (what Krakatoa, Frost, Stoke and Partio write):
//
//   header       8-byte magic C0 'P' 'R' 'T' '\r' '\n' 1A '\n', the header's length (int32,
//                56), "Extensible Particle Format" (32 bytes), the version (int32, 1), the
//                particle count (int64); little-endian throughout
//   channels     a reserved int32 (4), their count and each definition's length (int32, 44),
//                then per channel its name (32 bytes, NUL-terminated), type (int16, int32,
//                int64, float16, float32, float64, uint16, uint32, uint64, int8, uint8: 0..10),
//                arity and byte offset within a particle (int32 each)
//   data         one zlib stream holding the particles, each the same fixed record
//
// As Thinkbox's format description and Partio's reader (the field's reference) read it; longer
// headers and channel definitions of later versions are skipped by their stated lengths.
// Written by hand: no Debian package reads .prt (Partio is not packaged).
//
// "Position" (3 values) becomes the positions, "Normal" the normals; Krakatoa's other standard
// channels take the names the rest of the project uses ("Velocity" -> velocity, "Density" ->
// density, "Color" -> color, "ID" -> id); every other channel keeps its name.
#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include "io/compressed.h"
#include "io/file_reader.h"
#include "io/formats.h"
#include "io/scalar_types.h"
#include "io/text_numbers.h"
#include "particlemesh/core/error.h"

namespace PM_NAMESPACE::detail {

namespace {

constexpr unsigned char kMagic[8] = {0xC0, 'P', 'R', 'T', '\r', '\n', 0x1A, '\n'};
constexpr uint32_t kHeaderSize = 56, kChannelSize = 44;

struct Channel {
  std::string name;
  ScalarType type;
  uint32_t arity, offset;
};

ScalarType prt_type(uint32_t code) {
  static const ScalarType kTypes[11] = {ScalarType::I16, ScalarType::I32, ScalarType::I64, ScalarType::F16,
                                        ScalarType::F32, ScalarType::F64, ScalarType::U16, ScalarType::U32,
                                        ScalarType::U64, ScalarType::I8,  ScalarType::U8};
  return code < 11 ? kTypes[code] : ScalarType::None;
}

std::string project_name(const std::string& name) {
  if (name == "Velocity") return "velocity";
  if (name == "Density") return "density";
  if (name == "Color") return "color";
  if (name == "ID") return "id";
  return name;
}

}  // namespace

FileContents read_prt(const std::string& path, ReadPurpose) {
  auto fail = [&](const std::string& problem) { throw Error(Status::FormatError, "'" + path + "': " + problem); };
  // Read whole: the header's lengths say where the channels and the data start.
  std::string file = FileReader(path).read_rest();
  const auto* data = reinterpret_cast<const unsigned char*>(file.data());
  const size_t size = file.size();
  if (size < kHeaderSize || std::memcmp(data, kMagic, 8) != 0)
    fail("not a Krakatoa PRT file (it does not start with the PRT magic bytes)");
  const uint32_t header_size = load_little<uint32_t>(data + 8);
  const uint32_t version = load_little<uint32_t>(data + 44);
  const int64_t count = load_little<int64_t>(data + 48);
  if (header_size < kHeaderSize || header_size > size)
    fail("its header's length " + std::to_string(header_size) + " is not between 56 and the file's size");
  if (version < 1) fail("version " + std::to_string(version) + " is not a PRT version (1 and later are read)");
  if (count < 0) fail("the particle count " + std::to_string(count) + " is negative");
  size_t at = header_size;
  if (size - at < 12) fail("truncated: the file ends before its channel definitions");
  const uint32_t channels = load_little<uint32_t>(data + at + 4), definition = load_little<uint32_t>(data + at + 8);
  at += 12;
  if (definition < kChannelSize) fail("a channel definition of " + std::to_string(definition) + " bytes (44 expected)");
  if (channels == 0 || channels > 4096) fail(std::to_string(channels) + " channels (1 to 4096 are read)");
  if (uint64_t(channels) * definition > size - at) fail("truncated: the file ends in its channel definitions");

  std::vector<Channel> list;
  uint64_t record = 0;
  for (uint32_t c = 0; c < channels; ++c, at += definition) {
    const unsigned char* d = data + at;
    const size_t length = std::find(d, d + 32, 0) - d;
    Channel ch{std::string(reinterpret_cast<const char*>(d), length), prt_type(load_little<uint32_t>(d + 32)),
               load_little<uint32_t>(d + 36), load_little<uint32_t>(d + 40)};
    const std::string label = "channel " + std::to_string(c) + " '" + shown(ch.name) + "'";
    if (ch.name.empty()) fail("channel " + std::to_string(c) + " has no name");
    if (ch.type == ScalarType::None) fail(label + ": data type " + std::to_string(load_little<uint32_t>(d + 32)) + " is not 0..10");
    if (ch.arity < 1 || ch.arity > 1024) fail(label + ": arity " + std::to_string(ch.arity) + " (1 to 1024 are read)");
    record = std::max(record, uint64_t(ch.offset) + uint64_t(ch.arity) * uint64_t(scalar_size(ch.type)));
    list.push_back(std::move(ch));
  }
  if (record > (uint64_t(1) << 20)) fail("a particle record of " + std::to_string(record) + " bytes");
  const auto position = std::find_if(list.begin(), list.end(), [](const Channel& c) { return c.name == "Position"; });
  if (position == list.end()) fail("no Position channel");
  if (position->arity != 3) fail("the Position channel has " + std::to_string(position->arity) + " values (3 expected)");

  if (count == 0) return {};  // "holds no points", named by the caller
  // The particles: one zlib stream of count records. Deflate gives at most 1032 bytes per
  // byte, so a count the stream cannot hold is refused before anything is allocated.
  const uint64_t bytes = saturating_mul(uint64_t(count), record);
  const size_t compressed = size - at;
  if (bytes > max_decompressed_size(BlockCodec::Zlib, compressed))
    fail("truncated: " + std::to_string(count) + " particles of " + std::to_string(record) + " bytes cannot come from the " +
         std::to_string(compressed) + " compressed bytes left");
  std::vector<unsigned char> particles(static_cast<size_t>(bytes));
  decompress_block(BlockCodec::Zlib, data + at, compressed, particles.data(), particles.size(), path,
                   "the particle data");
  std::string().swap(file);  // the compressed bytes are not needed any more (`data` pointed into them)

  FileContents out;
  const size_t n = size_t(count);
  auto value = [&](const Channel& c, size_t i, uint32_t k) {
    return decode_scalar(c.type, particles.data() + i * record + c.offset + size_t(k) * size_t(scalar_size(c.type)), false);
  };
  out.positions.resize(n);
  for (size_t i = 0; i < n; ++i)
    out.positions[i] = {value(*position, i, 0), value(*position, i, 1), value(*position, i, 2)};
  for (const Channel& c : list) {
    if (&c == &*position) continue;
    if (c.name == "Normal" && c.arity == 3 && out.normals.empty()) {
      out.normals.resize(n);
      for (size_t i = 0; i < n; ++i) out.normals[i] = {value(c, i, 0), value(c, i, 1), value(c, i, 2)};
      continue;
    }
    VertexAttribute a{unique_attribute_name(out, project_name(c.name)), int(c.arity), {}};
    a.values.resize(n * c.arity);
    for (size_t i = 0; i < n; ++i)
      for (uint32_t k = 0; k < c.arity; ++k) a.values[i * c.arity + k] = float(value(c, i, k));
    out.attributes.push_back(std::move(a));
  }
  return out;
}

}  // namespace particlemesh::detail
