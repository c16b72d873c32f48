// VTK's XML formats for point sets, .vtu (UnstructuredGrid) and .vtp (PolyData), and their
// parallel forms .pvtu and .pvtp (a list of piece files, read and concatenated): data arrays
// in ascii, binary (base64) or appended (raw or base64) form, uncompressed or compressed with
// zlib, LZ4 or LZMA (vtkZLibDataCompressor, vtkLZ4DataCompressor, vtkLZMADataCompressor:
// ParaView's three choices), headers of UInt32 or UInt64, either byte order, any number of
// pieces. Raw appended data is what splashsurf fails on; it is read here like the rest.
//
// Written by hand for the reasons given at the top of vtk_legacy_reader.cpp (VTK's readers
// print and return partial data on hostile input; VTK's IO modules are 24 libraries for the
// add-on's zip). The XML part is small and regular: a tree of elements with attributes and
// text, read up to <AppendedData>, whose bytes are then addressed by each array's offset.
//
// What is read: the points (exactly: Float32, Float64 or integer components), every numeric
// PointData array as an attribute of its name (the one PointData's Normals="..." names, with
// 3 components, as the normals; a Bit array as 0 / 1), and for meshes the triangle, polygon
// and quad cells of an UnstructuredGrid or the Polys and Strips of a PolyData, fanned. String
// arrays (VTK writes them as <Array type="String">) are skipped and named in not_read.
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "io/compressed.h"
#include "io/file_reader.h"
#include "io/formats.h"
#include "io/scalar_types.h"
#include "io/text_numbers.h"
#include "particlemesh/core/error.h"

namespace PM_NAMESPACE::detail {

namespace {

struct Node {
  std::string name;
  std::vector<std::pair<std::string, std::string>> attributes;
  std::vector<Node> children;
  std::string text;  ///< the element's own character data

  const std::string* attribute(std::string_view key) const {
    for (const auto& [k, v] : attributes)
      if (k == key) return &v;
    return nullptr;
  }
  std::string get(std::string_view key, std::string fallback = {}) const {
    const std::string* v = attribute(key);
    return v ? *v : fallback;
  }
  const Node* child(std::string_view n) const {
    for (const Node& c : children)
      if (c.name == n) return &c;
    return nullptr;
  }
};

using Type = ScalarType;

Type type_of(const std::string& t) {
  if (t == "Int8" || t == "Char") return Type::I8;
  if (t == "UInt8" || t == "UChar") return Type::U8;
  if (t == "Int16" || t == "Short") return Type::I16;
  if (t == "UInt16" || t == "UShort") return Type::U16;
  if (t == "Int32" || t == "Int") return Type::I32;
  if (t == "UInt32" || t == "UInt") return Type::U32;
  if (t == "Int64" || t == "Long" || t == "IdType") return Type::I64;
  if (t == "UInt64" || t == "ULong") return Type::U64;
  if (t == "Float32" || t == "Float") return Type::F32;
  if (t == "Float64" || t == "Double") return Type::F64;
  if (t == "String") return Type::String;
  if (t == "Bit") return Type::Bit;
  return Type::None;
}

/// A value read from the file, for a message: any double (huge, NaN) without a cast.
std::string shown_number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", v);
  return text;
}

int base64_value(char c) {
  if (c >= 'A' && c <= 'Z') return c - 'A';
  if (c >= 'a' && c <= 'z') return c - 'a' + 26;
  if (c >= '0' && c <= '9') return c - '0' + 52;
  if (c == '+') return 62;
  if (c == '/') return 63;
  return -1;
}

bool xml_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }

class VtkXmlReader {
 public:
  /// `piece_of`: for a piece named by a parallel file, that file's serial type
  /// ("UnstructuredGrid" or "PolyData"), which the piece must have; empty for a file read alone.
  VtkXmlReader(const std::string& path, ReadPurpose purpose, std::string piece_of = {})
      : path_(path), purpose_(purpose), piece_of_(std::move(piece_of)) {}

  FileContents read() {
    const Node root = parse_root();
    if (appended_ != std::string::npos) {
      // The appended bytes run to </AppendedData></VTKFile> at the end of the file.
      size_t end = data_.size();
      while (end > appended_ && xml_space(data_[end - 1])) --end;
      const std::string_view tail = std::string_view(data_).substr(appended_, end - appended_);
      if (tail.size() < 10 || tail.substr(tail.size() - 10) != "</VTKFile>")
        fail("truncated: the file does not end with </VTKFile> after its appended data");
      appended_end_ = appended_ + tail.rfind("</AppendedData>");
      if (appended_end_ < appended_ || tail.rfind("</AppendedData>") == std::string_view::npos)
        fail("truncated: no </AppendedData> after the appended data");
    }
    const std::string type = root.get("type");
    if (type == "Collection")
      fail("a collection of frames (.pvd): mesh its frames as a sequence, the collection as the input of "
           "triangulate or polygonize with a frame field in the output (e.g. -o out/frame_{:04d}.ply)");
    if (type == "PUnstructuredGrid" || type == "PPolyData") {
      if (!piece_of_.empty()) fail("a piece of a parallel file is itself a parallel file (" + type + ")");
      return read_parallel(root, type);
    }
    if (type != "UnstructuredGrid" && type != "PolyData")
      fail("VTKFile type '" + shown(type) + "' is not a set of points (read: UnstructuredGrid .vtu, PolyData .vtp, " +
           "and their parallel .pvtu, .pvtp)");
    if (!piece_of_.empty() && type != piece_of_)
      fail("VTKFile type '" + type + "', but the parallel file that lists it has " + piece_of_ + " pieces");
    const std::string order = root.get("byte_order", "LittleEndian");
    if (order != "LittleEndian" && order != "BigEndian") fail("byte_order '" + shown(order) + "' is not LittleEndian or BigEndian");
    big_endian_ = order == "BigEndian";
    const std::string header = root.get("header_type", "UInt32");
    if (header != "UInt32" && header != "UInt64") fail("header_type '" + shown(header) + "' is not UInt32 or UInt64");
    header_size_ = header == "UInt64" ? 8 : 4;
    const std::string compressor = root.get("compressor");
    compressed_ = !compressor.empty();
    if (compressor == "vtkZLibDataCompressor") codec_ = BlockCodec::Zlib;
    else if (compressor == "vtkLZ4DataCompressor") codec_ = BlockCodec::Lz4;
    else if (compressor == "vtkLZMADataCompressor") codec_ = BlockCodec::Xz;
    else if (compressed_)
      fail("compressor '" + shown(compressor) + "' is not read (read: vtkZLibDataCompressor, vtkLZ4DataCompressor, "
           "vtkLZMADataCompressor)");

    const Node* set = root.child(type);
    if (!set) fail("<VTKFile type=\"" + type + "\"> holds no <" + type + "> element");
    collect_offsets(*set);
    bool any = false;
    for (const Node& piece : set->children)
      if (piece.name == "Piece") {
        read_piece(piece, type == "PolyData");
        any = true;
      }
    if (!any) fail("<" + type + "> holds no <Piece>");
    return std::move(out_);
  }

  /// A .pvd's frames: (timestep, file) of each <DataSet>, in the listed order.
  std::vector<std::pair<std::string, std::string>> collection() {
    const Node root = parse_root();
    const std::string type = root.get("type");
    if (type != "Collection")
      fail("VTKFile type '" + shown(type) + "' is not a Collection (a .pvd lists frames in <VTKFile type=\"Collection\">)");
    const Node* set = root.child("Collection");
    if (!set) fail("<VTKFile type=\"Collection\"> holds no <Collection> element");
    std::vector<std::pair<std::string, std::string>> out;
    for (const Node& d : set->children) {
      if (d.name != "DataSet") continue;
      const std::string label = "DataSet " + std::to_string(out.size());
      const std::string* time = d.attribute("timestep");
      const std::string* file = d.attribute("file");
      if (!file || file->empty()) fail(label + " has no file");
      if (!time) fail(label + " ('" + shown(*file) + "') has no timestep");
      out.emplace_back(*time, *file);
    }
    return out;
  }

 private:
  [[noreturn]] void fail(const std::string& problem) const {
    throw Error(Status::FormatError, "'" + path_ + "': " + problem);
  }

  /// The file's root element, <VTKFile>.
  Node parse_root() {
    data_ = FileReader(path_).read_rest();
    if (data_.empty()) fail("the file is empty");
    size_t p = 0;
    skip_misc(p);
    if (p >= data_.size() || data_[p] != '<') fail("not an XML file (VTK XML files start with '<?xml' or '<VTKFile')");
    Node root;
    parse_element(p, root, 0);
    if (root.name != "VTKFile") fail("not a VTK XML file (the root element is <" + shown(root.name) + ">, not <VTKFile>)");
    return root;
  }

  // ---- Parallel files ----------------------------------------------------------------------
  // A .pvtu / .pvtp (what ParaView and MPI simulations write, a piece per process) only lists
  // its pieces, each a serial file of the same kind; their points are concatenated in the
  // listed order, as VTK's parallel readers do. A piece is read only from the parallel file's
  // folder or below it (no absolute path, no '..'), only if it is a regular file (never a
  // device or a FIFO), and at most once: a hostile list cannot reach other files or make the
  // same large file count many times.
  FileContents read_parallel(const Node& root, const std::string& type) {
    namespace fs = std::filesystem;
    const std::string serial = type.substr(1);
    const Node* set = root.child(type);
    if (!set) fail("<VTKFile type=\"" + type + "\"> holds no <" + type + "> element");
    const fs::path folder = fs::path(path_).parent_path();
    std::vector<std::string> sources;
    for (const Node& piece : set->children) {
      if (piece.name != "Piece") continue;
      const std::string label = "piece " + std::to_string(sources.size());
      const std::string source = piece.get("Source");
      if (source.empty()) fail(label + " has no Source file");
      std::string portable;
      if (!path_inside_folder(source, portable))
        fail(label + "'s Source '" + shown(source) + "' is not a path inside the parallel file's folder (pieces are " +
             "read only from beside it or below it)");
      if (std::find(sources.begin(), sources.end(), source) != sources.end())
        fail(label + " repeats the Source '" + shown(source) + "' of an earlier piece");
      sources.push_back(source);
      const fs::path file = folder / fs::path(portable);
      std::error_code ec;
      if (!fs::exists(file, ec)) fail(label + "'s Source '" + shown(source) + "' does not exist (" + file.string() + ")");
      if (!fs::is_regular_file(file, ec))
        fail(label + "'s Source '" + shown(source) + "' is not a regular file (" + file.string() + ")");
      add_piece_file(VtkXmlReader(file.string(), purpose_, serial).read(), label + " ('" + shown(source) + "')");
    }
    if (sources.empty()) fail("<" + type + "> lists no <Piece Source=\"...\">");
    return std::move(out_);
  }

  /// Appends a piece file's contents; every piece with points must carry the same point arrays
  /// (names and components) and normals as the first one.
  void add_piece_file(FileContents&& c, const std::string& label) {
    out_.faces += c.faces;
    for (std::string& what : c.not_read) note_not_read(out_, std::move(what));
    out_.not_read_more += c.not_read_more;
    if (c.positions.empty()) return;  // a process that held no particles
    if (out_.positions.empty()) {
      const uint64_t faces = out_.faces;
      std::vector<std::string> not_read = std::move(out_.not_read);
      const uint64_t more = out_.not_read_more;
      out_ = std::move(c);
      out_.faces = faces;
      out_.not_read = std::move(not_read);
      out_.not_read_more = more;
      return;
    }
    bool same = c.attributes.size() == out_.attributes.size() && c.normals.empty() == out_.normals.empty();
    for (size_t a = 0; same && a < c.attributes.size(); ++a)
      same = c.attributes[a].name == out_.attributes[a].name && c.attributes[a].components == out_.attributes[a].components;
    if (!same) fail(label + " carries other point arrays than the first piece (pieces must carry the same arrays)");
    const size_t base = out_.positions.size();
    if (!c.triangles.empty() && base + c.positions.size() > size_t(UINT32_MAX))
      fail(label + ": the pieces hold more than 2^32 points with cells");
    out_.positions.insert(out_.positions.end(), c.positions.begin(), c.positions.end());
    out_.normals.insert(out_.normals.end(), c.normals.begin(), c.normals.end());
    for (size_t a = 0; a < c.attributes.size(); ++a)
      out_.attributes[a].values.insert(out_.attributes[a].values.end(), c.attributes[a].values.begin(),
                                       c.attributes[a].values.end());
    out_.triangles.reserve(out_.triangles.size() + c.triangles.size());
    for (const Triangle& t : c.triangles)
      out_.triangles.push_back({uint32_t(base + t[0]), uint32_t(base + t[1]), uint32_t(base + t[2])});
  }

  // ---- XML --------------------------------------------------------------------------------
  void skip_misc(size_t& p) {
    while (true) {
      while (p < data_.size() && xml_space(data_[p])) ++p;
      if (data_.compare(p, 4, "<!--") == 0) {
        const size_t e = data_.find("-->", p + 4);
        if (e == std::string::npos) fail("truncated: an XML comment is not closed");
        p = e + 3;
      } else if (data_.compare(p, 2, "<?") == 0) {
        const size_t e = data_.find("?>", p + 2);
        if (e == std::string::npos) fail("truncated: an XML declaration is not closed");
        p = e + 2;
      } else if (data_.compare(p, 2, "<!") == 0) {
        const size_t e = data_.find('>', p + 2);
        if (e == std::string::npos) fail("truncated: an XML declaration is not closed");
        p = e + 1;
      } else {
        return;
      }
    }
  }

  std::string unescape(std::string_view s) const {
    std::string out;
    for (size_t i = 0; i < s.size(); ++i) {
      if (s[i] != '&') {
        out.push_back(s[i]);
        continue;
      }
      const size_t e = s.find(';', i);
      if (e == std::string_view::npos) {
        out.push_back('&');
        continue;
      }
      const std::string_view ent = s.substr(i + 1, e - i - 1);
      if (ent == "lt") out.push_back('<');
      else if (ent == "gt") out.push_back('>');
      else if (ent == "amp") out.push_back('&');
      else if (ent == "quot") out.push_back('"');
      else if (ent == "apos") out.push_back('\'');
      else out.append(s.substr(i, e - i + 1));
      i = e;
    }
    return out;
  }

  std::string name_at(size_t& p) {
    const size_t b = p;
    while (p < data_.size() && !xml_space(data_[p]) && data_[p] != '>' && data_[p] != '/' && data_[p] != '=') ++p;
    return data_.substr(b, p - b);
  }

  /// The element at p ('<'), its attributes, text and children, up to its end tag (or to
  /// <AppendedData>'s bytes, after which nothing is parsed as XML).
  void parse_element(size_t& p, Node& node, int depth) {
    if (depth > 64) fail("XML elements nested more than 64 deep");
    ++p;  // '<'
    node.name = name_at(p);
    if (node.name.empty()) fail("bad XML at byte " + std::to_string(p) + " (an element without a name)");
    while (true) {
      while (p < data_.size() && xml_space(data_[p])) ++p;
      if (p >= data_.size()) fail("truncated: the file ends inside the tag <" + shown(node.name) + ">");
      if (data_[p] == '/') {
        if (data_.compare(p, 2, "/>") != 0) fail("bad XML in the tag <" + shown(node.name) + ">");
        p += 2;
        return;
      }
      if (data_[p] == '>') {
        ++p;
        break;
      }
      std::string key = name_at(p);
      while (p < data_.size() && xml_space(data_[p])) ++p;
      if (key.empty() || p >= data_.size() || data_[p] != '=')
        fail("bad XML attribute in the tag <" + shown(node.name) + "> at byte " + std::to_string(p));
      ++p;
      while (p < data_.size() && xml_space(data_[p])) ++p;
      if (p >= data_.size() || (data_[p] != '"' && data_[p] != '\''))
        fail("bad XML attribute '" + shown(key) + "' in <" + shown(node.name) + "> (no quoted value)");
      const char q = data_[p++];
      const size_t e = data_.find(q, p);
      if (e == std::string::npos) fail("truncated: the file ends inside the tag <" + shown(node.name) + ">");
      node.attributes.emplace_back(std::move(key), unescape(std::string_view(data_).substr(p, e - p)));
      p = e + 1;
    }
    if (node.name == "AppendedData") {
      const std::string encoding = node.get("encoding", "raw");
      if (encoding != "raw" && encoding != "base64") fail("AppendedData encoding '" + shown(encoding) + "' is not raw or base64");
      appended_base64_ = encoding == "base64";
      while (p < data_.size() && xml_space(data_[p])) ++p;
      if (p >= data_.size() || data_[p] != '_') fail("the appended data does not start with '_'");
      appended_ = p + 1;
      p = data_.size();
      return;
    }
    while (true) {
      const size_t lt = data_.find('<', p);
      if (lt == std::string::npos) fail("truncated: <" + shown(node.name) + "> is not closed");
      node.text.append(data_, p, lt - p);
      p = lt;
      if (data_.compare(p, 4, "<!--") == 0 || data_.compare(p, 2, "<?") == 0) {
        skip_misc(p);
        continue;
      }
      if (data_.compare(p, 2, "</") == 0) {
        p += 2;
        const std::string end = name_at(p);
        if (end != node.name) fail("bad XML: <" + shown(node.name) + "> is closed by </" + shown(end) + ">");
        while (p < data_.size() && xml_space(data_[p])) ++p;
        if (p >= data_.size() || data_[p] != '>') fail("bad XML in </" + shown(end) + ">");
        ++p;
        return;
      }
      node.children.emplace_back();
      parse_element(p, node.children.back(), depth + 1);
      if (appended_ != std::string::npos) return;  // the rest is appended data
    }
  }

  // ---- arrays -------------------------------------------------------------------------------
  void collect_offsets(const Node& n) {
    if (n.name == "DataArray" && n.get("format") == "appended") {
      uint64_t o = 0;
      if (parse_count(n.get("offset"), o)) offsets_.push_back(o);
    }
    for (const Node& c : n.children) collect_offsets(c);
    std::sort(offsets_.begin(), offsets_.end());
  }

  /// Lenient base64: '=' may end any group of four (VTK encodes a compressed array's header
  /// and its blocks separately), whitespace is ignored.
  std::vector<unsigned char> base64(std::string_view s, const std::string& what) const {
    std::vector<unsigned char> out;
    out.reserve(s.size() / 4 * 3 + 3);
    int group[4], n = 0, pad = 0;
    for (char c : s) {
      if (xml_space(c)) continue;
      if (c == '=') {
        if (n < 2) fail(what + ": bad base64 padding");
        ++pad;
        group[n++] = 0;
      } else {
        const int v = base64_value(c);
        if (v < 0 || pad) fail(what + ": not base64 data (the character '" + shown(std::string(1, c)) + "')");
        group[n++] = v;
      }
      if (n == 4) {
        const uint32_t w = uint32_t(group[0]) << 18 | uint32_t(group[1]) << 12 | uint32_t(group[2]) << 6 | uint32_t(group[3]);
        out.push_back(uint8_t(w >> 16));
        if (pad < 2) out.push_back(uint8_t(w >> 8));
        if (pad < 1) out.push_back(uint8_t(w));
        n = pad = 0;
      }
    }
    if (n != 0) fail(what + ": truncated base64 data");
    return out;
  }

  /// A UInt32 / UInt64 header word, read as an integer (through a double, a UInt64 near
  /// 2^64 would round beyond the type).
  uint64_t header_value(const unsigned char* b) const {
    uint64_t v = 0;
    for (size_t i = 0; i < header_size_; ++i) {
      const size_t k = big_endian_ ? i : header_size_ - 1 - i;
      v = v << 8 | b[k];
    }
    return v;
  }

  /// Where the values of an uncompressed array start (after its header), checked to hold
  /// `expected` bytes.
  const unsigned char* uncompressed(const unsigned char* b, size_t size, uint64_t expected, const std::string& what) const {
    const size_t hs = header_size_;
    if (hs > size) fail("truncated: " + what + " needs " + std::to_string(hs) + " bytes for its header, the data holds " + std::to_string(size));
    const uint64_t bytes = header_value(b);
    if (bytes != expected) fail(what + " holds " + std::to_string(bytes) + " bytes, expected " + std::to_string(expected));
    if (bytes > size - hs)
      fail("truncated: " + what + " needs " + std::to_string(hs + bytes) + " bytes for its values, the data holds " +
           std::to_string(size));
    return b + hs;
  }

  /// The payload bytes of a binary or appended array: header + data, or header + compressed blocks.
  std::vector<unsigned char> payload(const unsigned char* b, size_t size, uint64_t expected, const std::string& what) const {
    const size_t hs = header_size_;
    auto need = [&](uint64_t bytes, const char* where) {
      if (bytes > size)
        fail("truncated: " + what + " needs " + std::to_string(bytes) + " bytes " + where + ", the data holds " +
             std::to_string(size));
    };
    std::vector<unsigned char> out;
    if (!compressed_) {
      const unsigned char* v = uncompressed(b, size, expected, what);
      out.assign(v, v + expected);
      return out;
    }
    need(3 * hs, "for its compression header");
    const uint64_t blocks = header_value(b), block = header_value(b + hs), last = header_value(b + 2 * hs);
    if (blocks > size / hs) fail(what + ": its compression header lists " + std::to_string(blocks) + " blocks");
    need((3 + blocks) * hs, "for its compression header");
    const uint64_t total = blocks == 0 ? 0 : saturating_mul(blocks - 1, block) + (last == 0 ? block : last);
    if (total != expected || (last > block && blocks > 0))
      fail(what + ": its compressed blocks hold " + std::to_string(total) + " bytes, expected " + std::to_string(expected));
    // The output grows block by block, each checked against what its codec can give from its
    // compressed bytes (max_decompressed_size): a header claiming more allocates nothing.
    out.reserve(size_t(std::min<uint64_t>(total, uint64_t(1) << 24)));
    uint64_t at = (3 + blocks) * hs, made = 0;
    for (uint64_t k = 0; k < blocks; ++k) {
      const uint64_t csize = header_value(b + (3 + k) * hs);
      need(at + csize, "for its compressed blocks");
      const uint64_t usize = k + 1 == blocks && last != 0 ? last : block;
      if (usize > max_decompressed_size(codec_, csize))
        fail(what + ", block " + std::to_string(k) + ": " + std::to_string(csize) + " compressed bytes cannot hold the " +
             std::to_string(usize) + " its header claims");
      out.resize(size_t(made + usize));
      decompress_block(codec_, b + at, size_t(csize), out.data() + made, size_t(usize), path_, what + ", block " + std::to_string(k));
      at += csize;
      made += usize;
    }
    return out;
  }

  /// The values of a DataArray, tuples x its components, as doubles.
  std::vector<double> array(const Node& a, uint64_t tuples, int* components, const std::string& what) const {
    const Type type = type_of(a.get("type"));
    if (type == Type::None || type == Type::String)
      fail(what + ": data type '" + shown(a.get("type")) + "' is not numeric");
    uint64_t comps = 1;
    if (a.attribute("NumberOfComponents") && (!parse_count(a.get("NumberOfComponents"), comps) || comps < 1 || comps > 65535))
      fail(what + ": NumberOfComponents '" + shown(a.get("NumberOfComponents")) + "'");
    *components = int(comps);
    const uint64_t count = saturating_mul(tuples, comps);
    const std::string format = a.get("format", "ascii");
    std::vector<double> out;
    if (format == "ascii") {
      out.reserve(size_t(std::min<uint64_t>(count, a.text.size() / 2 + 1)));
      size_t p = 0;
      const std::string& t = a.text;
      while (true) {
        while (p < t.size() && xml_space(t[p])) ++p;
        if (p >= t.size()) break;
        size_t e = p;
        while (e < t.size() && !xml_space(t[e])) ++e;
        double v = 0;
        if (parse_number(std::string_view(t).substr(p, e - p), v) != NumberText::Ok)
          fail(what + ", value " + std::to_string(out.size()) + ": not a number: '" + shown(t.substr(p, e - p)) + "'");
        out.push_back(v);
        p = e;
      }
      if (out.size() != count)
        fail(what + " holds " + std::to_string(out.size()) + " values, expected " + std::to_string(count) + " (" +
             std::to_string(tuples) + " x " + std::to_string(comps) + ")");
      return out;
    }
    const bool bits = type == Type::Bit;
    const int size = scalar_size(type);
    const uint64_t expected = bits ? bit_bytes(count) : saturating_mul(count, uint64_t(size));
    std::vector<unsigned char> bytes;
    const unsigned char* values = nullptr;  // bytes.data(), or raw appended data in place
    if (format == "binary") {
      const std::vector<unsigned char> raw = base64(a.text, what);
      bytes = payload(raw.data(), raw.size(), expected, what);
    } else if (format == "appended") {
      if (appended_ == std::string::npos) fail(what + " is appended, but the file has no <AppendedData>");
      uint64_t offset = 0;
      if (!parse_count(a.get("offset"), offset)) fail(what + ": bad offset '" + shown(a.get("offset")) + "'");
      const size_t length = appended_end_ - appended_;
      if (offset >= length) fail("truncated: " + what + " starts at appended byte " + std::to_string(offset) + ", the appended data has " + std::to_string(length));
      const unsigned char* base = reinterpret_cast<const unsigned char*>(data_.data()) + appended_ + offset;
      if (appended_base64_) {
        const auto next = std::upper_bound(offsets_.begin(), offsets_.end(), offset);
        size_t end = next == offsets_.end() ? length : size_t(*next);
        std::string_view chars(reinterpret_cast<const char*>(base), end - size_t(offset));
        const size_t stop = chars.find('<');
        if (stop != std::string_view::npos) chars = chars.substr(0, stop);
        const std::vector<unsigned char> raw = base64(chars, what);
        bytes = payload(raw.data(), raw.size(), expected, what);
      } else if (!compressed_) {
        values = uncompressed(base, length - size_t(offset), expected, what);
      } else {
        bytes = payload(base, length - size_t(offset), expected, what);
      }
    } else {
      fail(what + ": format '" + shown(format) + "' is not ascii, binary or appended");
    }
    out.resize(size_t(count));
    const unsigned char* from = values ? values : bytes.data();
    if (bits) decode_bits(from, size_t(count), out.data());
    else decode_scalars(type, from, size_t(count), big_endian_, out.data());
    return out;
  }

  void read_piece(const Node& piece, bool polydata) {
    uint64_t n = 0;
    if (!parse_count(piece.get("NumberOfPoints"), n)) fail("<Piece> has no NumberOfPoints");
    const std::string label = "piece " + std::to_string(pieces_++);
    const size_t base = out_.positions.size();
    if (n > 0) {
      const Node* points = piece.child("Points");
      const Node* pa = points ? points->child("DataArray") : nullptr;
      if (!pa) fail(label + " has no <Points><DataArray>");
      int comps = 0;
      const std::vector<double> p = array(*pa, n, &comps, label + " Points");
      if (comps != 3) fail(label + " Points have " + std::to_string(comps) + " components (3 expected)");
      out_.positions.reserve(base + size_t(n));
      for (uint64_t i = 0; i < n; ++i) out_.positions.push_back({p[3 * i], p[3 * i + 1], p[3 * i + 2]});
    }
    if (const Node* pd = piece.child("PointData")) {
      const std::string normals = pd->get("Normals");
      for (const Node& a : pd->children) {
        const std::string name = a.get("Name");
        if (a.name == "Array") {  // VTK's element for arrays of other than numbers (vtkStringArray)
          const std::string type = a.get("type");
          const std::string kind = type == "String" ? "strings" : shown(type) + " values";
          note_not_read(out_, "PointData array '" + shown(name) + "' (" + kind + ")");
          continue;
        }
        if (a.name != "DataArray") continue;
        const std::string what = label + " PointData array '" + shown(name) + "'";
        if (type_of(a.get("type")) == Type::String) {  // not a per-point number
          note_not_read(out_, "PointData array '" + shown(name) + "' (strings)");
          continue;
        }
        int comps = 0;
        std::vector<double> v = array(a, n, &comps, what);
        if (!normals.empty() && name == normals && comps == 3 && (pieces_ == 1 || normals_)) {
          normals_ = true;
          for (uint64_t i = 0; i < n; ++i) out_.normals.push_back({v[3 * i], v[3 * i + 1], v[3 * i + 2]});
          continue;
        }
        VertexAttribute* target = nullptr;
        if (pieces_ > 1) {
          for (VertexAttribute& x : out_.attributes)
            if (x.name == name && x.components == comps) target = &x;
          if (!target) fail(what + " is not in the first piece (pieces must carry the same arrays)");
        } else {
          out_.attributes.push_back({unique_attribute_name(out_, name.empty() ? "array" : name), comps, {}});
          target = &out_.attributes.back();
        }
        target->values.reserve(target->values.size() + v.size());
        for (double x : v) target->values.push_back(float(x));
      }
    }
    for (const VertexAttribute& x : out_.attributes)
      if (x.values.size() != out_.positions.size() * size_t(x.components))
        fail(label + " lacks PointData array '" + shown(x.name) + "' (pieces must carry the same arrays)");
    if (normals_ && out_.normals.size() != out_.positions.size()) fail(label + " lacks the normals array");
    if (purpose_ == ReadPurpose::Mesh) {
      read_cells(piece, polydata, base, n, label);
      if (const Node* cd = piece.child("CellData"))  // per cell: nothing a triangle mesh's vertices carry
        for (const Node& a : cd->children)
          if (a.name == "DataArray" || a.name == "Array")
            note_not_read(out_, "CellData array '" + shown(a.get("Name")) + "'");
    }
  }

  void read_cells(const Node& piece, bool polydata, size_t base, uint64_t n, const std::string& label) {
    auto find = [&](const Node* parent, const char* name) -> const Node* {
      if (!parent) return nullptr;
      for (const Node& c : parent->children)
        if (c.name == "DataArray" && c.get("Name") == name) return &c;
      return nullptr;
    };
    auto add = [&](const Node* parent, const char* kind, uint64_t cells, bool strips, const std::vector<double>* types) {
      const Node* conn = find(parent, "connectivity");
      const Node* offs = find(parent, "offsets");
      if (!conn || !offs) fail(label + " " + kind + ": no connectivity and offsets arrays");
      int c = 0;
      const std::vector<double> offsets = array(*offs, cells, &c, label + " " + kind + " offsets");
      const double total = offsets.empty() ? 0 : offsets.back();
      if (!(total >= 0 && total <= 4e9)) fail(label + " " + kind + ": the offsets end at " + std::to_string(total));
      const std::vector<double> ids = array(*conn, uint64_t(total), &c, label + " " + kind + " connectivity");
      double begin = 0;
      for (uint64_t k = 0; k < cells; ++k) {
        const double end = offsets[k];
        if (!(end >= begin && end <= total)) fail(label + " " + kind + ": offset " + std::to_string(k) + " goes backwards");
        const size_t b = size_t(begin), e = size_t(end);
        begin = end;
        if (types) {
          const double t = (*types)[k];
          if (t != 5 && t != 7 && t != 9) continue;
        }
        ++out_.faces;
        auto corner = [&](size_t i) -> uint32_t {
          if (!(ids[i] >= 0 && ids[i] < double(n)))
            fail(label + " " + kind + ": cell " + std::to_string(k) + " refers to point " + shown_number(ids[i]) +
                 " (the piece has " + std::to_string(n) + ")");
          return uint32_t(base + size_t(ids[i]));
        };
        if (e - b < 3) continue;
        for (size_t i = b; i + 2 < e && strips; ++i) {
          if ((i - b) % 2 == 0) out_.triangles.push_back({corner(i), corner(i + 1), corner(i + 2)});
          else out_.triangles.push_back({corner(i + 1), corner(i), corner(i + 2)});
        }
        for (size_t i = b + 1; i + 1 < e && !strips; ++i) out_.triangles.push_back({corner(b), corner(i), corner(i + 1)});
      }
    };
    if (polydata) {
      uint64_t polys = 0, strips = 0;
      parse_count(piece.get("NumberOfPolys", "0"), polys);
      parse_count(piece.get("NumberOfStrips", "0"), strips);
      if (polys) add(piece.child("Polys"), "Polys", polys, false, nullptr);
      if (strips) add(piece.child("Strips"), "Strips", strips, true, nullptr);
    } else {
      uint64_t cells = 0;
      parse_count(piece.get("NumberOfCells", "0"), cells);
      if (cells == 0) return;
      const Node* cs = piece.child("Cells");
      const Node* ta = find(cs, "types");
      if (!ta) fail(label + " Cells: no types array");
      int c = 0;
      const std::vector<double> types = array(*ta, cells, &c, label + " Cells types");
      add(cs, "Cells", cells, false, &types);
    }
  }

  std::string path_;
  ReadPurpose purpose_;
  std::string piece_of_;
  std::string data_;
  size_t appended_ = std::string::npos, appended_end_ = 0;
  bool appended_base64_ = false;
  bool big_endian_ = false;
  bool compressed_ = false;
  BlockCodec codec_ = BlockCodec::Zlib;
  bool normals_ = false;
  size_t header_size_ = 4;
  size_t pieces_ = 0;
  std::vector<uint64_t> offsets_;
  FileContents out_;
};

}  // namespace

FileContents read_vtk_xml(const std::string& path, ReadPurpose purpose) { return VtkXmlReader(path, purpose).read(); }

std::vector<std::pair<std::string, std::string>> read_pvd_entries(const std::string& path) {
  return VtkXmlReader(path, ReadPurpose::Points).collection();
}

}  // namespace particlemesh::detail
