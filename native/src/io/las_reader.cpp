// ASPRS LAS lidar point files, versions 1.0 to 1.4, point data record formats 0 to 10, as the
// ASPRS LAS specification (1.4 R15) lays them out: a public header (signature "LASF", the
// point format, the record length, the point count, the coordinates' scales and offsets),
// variable length records (skipped), then fixed-length point records; little-endian.
//
// Read: the positions (X Y Z as 32-bit integers, times the scale plus the offset, in double),
// and as channels "intensity", "classification" and, in the formats that carry it, "color"
// (red green blue, 16-bit in the specification: divided by 65535, or by 255 where no value
// exceeds 255, as some writers store 8-bit values). The other standard fields, and bytes a
// writer adds after them ("extra bytes"), are skipped and named in FileContents::not_read.
// LAZ (compressed LAS, the point format's top bits set) is refused with a message saying how
// to decompress it.
//
// Written by hand: Debian's PDAL and libLAS would bring large dependency trees into the core
// library for a format whose uncompressed form is a header and fixed records.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "io/file_reader.h"
#include "io/formats.h"
#include "io/scalar_types.h"
#include "particlemesh/core/error.h"

namespace PM_NAMESPACE::detail {

namespace {

/// The standard fields' size of each point data record format, and where its colour lies
/// (0: none).
struct RecordLayout {
  uint16_t size;
  uint16_t color;
  bool extended;  ///< formats 6-10: 16-bit scan angle, classification at byte 16
};
constexpr RecordLayout kLayouts[11] = {{20, 0, false},  {28, 0, false},  {26, 20, false}, {34, 28, false},
                                       {57, 0, false},  {63, 28, false}, {30, 0, true},   {36, 30, true},
                                       {38, 30, true},  {59, 0, true},   {67, 30, true}};

}  // namespace

FileContents read_las(const std::string& path, ReadPurpose) {
  auto fail = [&](const std::string& problem) { throw Error(Status::FormatError, "'" + path + "': " + problem); };
  FileReader in(path);
  unsigned char h[375] = {};
  if (!in.read(h, 227)) fail("truncated: the file is shorter than a LAS header (227 bytes)");
  if (std::memcmp(h, "LASF", 4) != 0) fail("not a LAS file (it does not start with 'LASF')");
  const int major = h[24], minor = h[25];
  const uint16_t header_size = load_little<uint16_t>(h + 94);
  const uint32_t data_offset = load_little<uint32_t>(h + 96);
  const uint8_t format_byte = h[104];
  const uint16_t record_length = load_little<uint16_t>(h + 105);
  if (major != 1 || minor > 4)
    fail("LAS version " + std::to_string(major) + "." + std::to_string(minor) + " is not read (1.0 to 1.4 are)");
  if (format_byte & 0xC0)
    fail("this is LAZ (compressed LAS), which is not read: decompress it first (laszip -i in.laz -o out.las, or "
         "pdal translate in.laz out.las)");
  if (format_byte > 10) fail("point data record format " + std::to_string(format_byte) + " is not read (0 to 10 are)");
  const RecordLayout layout = kLayouts[format_byte];
  if (record_length < layout.size)
    fail("point data records of " + std::to_string(record_length) + " bytes are shorter than format " +
         std::to_string(format_byte) + "'s " + std::to_string(layout.size));
  if (header_size < 227 || data_offset < header_size) fail("its header size or point data offset is inconsistent");
  uint64_t count = load_little<uint32_t>(h + 107);
  if (minor >= 4 && header_size >= 375) {
    if (!in.read(h + 227, 375 - 227)) fail("truncated: the file ends in its LAS 1.4 header");
    const uint64_t count14 = load_little<uint64_t>(h + 247);
    if (count14 != 0) count = count14;
  }
  const double scale[3] = {load_little<double>(h + 131), load_little<double>(h + 139), load_little<double>(h + 147)};
  const double offset[3] = {load_little<double>(h + 155), load_little<double>(h + 163), load_little<double>(h + 171)};
  for (double s : scale)
    if (!(s > 0 || s < 0) || !std::isfinite(s)) fail("a coordinate scale factor is zero or not finite");
  // Skip the rest of the header and the variable length records up to the points.
  if (!in.skip(data_offset - in.offset())) fail("truncated: the file ends before its point data");
  const uint64_t left = in.size() > 0 ? uint64_t(in.size()) - in.offset() : UINT64_MAX;
  if (saturating_mul(count, record_length) > left)
    fail("truncated: " + std::to_string(count) + " points of " + std::to_string(record_length) +
         " bytes, but the file holds " + std::to_string(left) + " bytes of point data");

  // Read in chunks, the arrays growing with what was read (a FIFO has no size to check the
  // count against).
  FileContents out;
  const uint64_t n = count;
  const size_t expect = size_t(std::min<uint64_t>(n, uint64_t(1) << 22));
  out.positions.reserve(expect);
  VertexAttribute intensity{"intensity", 1, {}};
  VertexAttribute classification{"classification", 1, {}};
  VertexAttribute color{"color", 3, {}};
  intensity.values.reserve(expect);
  classification.values.reserve(expect);
  std::vector<uint16_t> rgb;
  std::vector<unsigned char> buf(size_t(record_length) * 4096);
  for (uint64_t i = 0; i < n;) {
    const size_t k = size_t(std::min<uint64_t>(4096, n - i));
    if (!in.read(buf.data(), k * record_length)) fail("truncated: the file ends in point " + std::to_string(i));
    for (size_t j = 0; j < k; ++j) {
      const unsigned char* r = buf.data() + j * record_length;
      out.positions.push_back({double(load_little<int32_t>(r + 0)) * scale[0] + offset[0],
                               double(load_little<int32_t>(r + 4)) * scale[1] + offset[1],
                               double(load_little<int32_t>(r + 8)) * scale[2] + offset[2]});
      intensity.values.push_back(float(load_little<uint16_t>(r + 12)));
      classification.values.push_back(float(layout.extended ? r[16] : (r[15] & 0x1F)));
      if (layout.color)
        for (size_t c = 0; c < 3; ++c) rgb.push_back(load_little<uint16_t>(r + layout.color + 2 * c));
    }
    i += k;
  }
  out.attributes.push_back(std::move(intensity));
  out.attributes.push_back(std::move(classification));
  if (layout.color) {
    const uint16_t top = rgb.empty() ? 0 : *std::max_element(rgb.begin(), rgb.end());
    const float scale_rgb = top <= 255 ? 1.0f / 255.0f : 1.0f / 65535.0f;
    color.values.resize(rgb.size());
    for (size_t c = 0; c < rgb.size(); ++c) color.values[c] = float(rgb[c]) * scale_rgb;
    out.attributes.push_back(std::move(color));
  }
  // What else each record holds, said rather than dropped silently.
  const bool gps = format_byte != 0 && format_byte != 2, nir = format_byte == 8 || format_byte == 10,
             waves = format_byte == 4 || format_byte == 5 || format_byte == 9 || format_byte == 10;
  note_not_read(out, std::string("the LAS fields return number, number of returns, scan angle, user data, point source ID") +
                         (gps ? ", GPS time" : "") + (nir ? ", NIR" : "") + (waves ? ", wave packet" : ""));
  if (record_length > layout.size)
    note_not_read(out, "extra bytes (" + std::to_string(record_length - layout.size) + " per point)");
  return out;
}

}  // namespace particlemesh::detail
