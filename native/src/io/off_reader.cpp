// OFF (Geomview's Object File Format), ASCII: [ST][C][N]OFF, then the vertex, face and edge
// counts, the vertices (x y z, nx ny nz with N; colours and texture coordinates on the rest
// of the line are skipped) and the faces (a corner count, the indices, an optional colour on
// the rest of the line). '#' starts a comment anywhere. Written by hand (a few dozen lines;
// OpenMesh's reader, the one we had, kept float32, read counts from a failed stream and
// looped on them). Binary OFF and 4D / n-D variants are refused by name.
#include <cctype>
#include <cmath>
#include <string>

#include "io/file_reader.h"
#include "io/formats.h"
#include "io/text_numbers.h"
#include "particlemesh/core/error.h"

namespace PM_NAMESPACE::detail {

namespace {

class OffReader {
 public:
  OffReader(const std::string& path, ReadPurpose purpose) : in_(path), purpose_(purpose) {}

  FileContents read() {
    if (in_.peek() < 0) fail("the file is empty");
    bool ended = false;
    if (!next(&ended)) fail("the file is empty");
    // The keyword: [ST][C][N][4][n]OFF. ModelNet's files glue the vertex count to it
    // ("OFF490 518 0"): the digits after OFF are the first count.
    size_t off = tok_.rfind("OFF");
    if (off != std::string::npos && off + 3 < tok_.size() && std::isdigit(static_cast<unsigned char>(tok_[off + 3]))) {
      pending_ = tok_.substr(off + 3);
      tok_.resize(off + 3);
    }
    if (off == std::string::npos || off + 3 != tok_.size()) fail("not an OFF file (no OFF keyword first)");
    const std::string prefix = tok_.substr(0, off);
    size_t k = 0;
    if (prefix.compare(k, 2, "ST") == 0) k += 2;
    if (k < prefix.size() && prefix[k] == 'C') ++k;
    if (k < prefix.size() && prefix[k] == 'N') normals_ = true, ++k;
    if (k < prefix.size() && (prefix[k] == '4' || prefix[k] == 'n'))
      fail("4D / n-dimensional OFF ('" + shown(tok_) + "') is not read: 3D only");
    if (k != prefix.size()) fail("unknown OFF keyword '" + shown(tok_) + "'");
    uint64_t counts[3] = {0, 0, 0};
    for (int c = 0; c < 3; ++c) {
      if (!next(&ended)) {
        if (c == 2) break;  // the edge count is often left out at the very end of an empty mesh
        fail("truncated OFF header (no vertex and face counts)");
      }
      if (c == 0 && tok_ == "BINARY") fail("binary OFF is not read (write it as ASCII OFF, PLY or OBJ)");
      if (!parse_count(tok_, counts[c])) fail("bad OFF header: '" + shown(tok_) + "' is not a vertex/face/edge count");
    }
    if (!ended) in_.skip_line();
    nv_ = counts[0];
    nf_ = counts[1];
    FileContents out;
    out.faces = nf_;
    const uint64_t left = in_.size() < 0 ? (uint64_t(1) << 16) : uint64_t(in_.size()) / 6;
    out.positions.reserve(size_t(std::min(nv_, left)));
    if (normals_) out.normals.reserve(size_t(std::min(nv_, left)));
    for (uint64_t v = 0; v < nv_; ++v) {
      double c[6] = {0, 0, 0, 0, 0, 0};
      for (int i = 0; i < (normals_ ? 6 : 3); ++i) {
        if (!next(&ended)) truncated("vertex " + std::to_string(v));
        double x = 0;
        if (parse_number(tok_, x) != NumberText::Ok)
          fail("vertex " + std::to_string(v) + ": '" + shown(tok_) + "' is " +
               (parse_number(tok_, x) == NumberText::Overflow ? "beyond the range of double (1.8e308)" : "not a number"));
        c[i] = x;
      }
      out.positions.push_back({c[0], c[1], c[2]});
      if (normals_) out.normals.push_back({c[3], c[4], c[5]});
      if (!ended) {  // colours, texture coordinates (or a comment)
        extra_vertex_values_ = extra_vertex_values_ || in_.look_ahead(1) != "#";
        in_.skip_line();
      }
    }
    for (uint64_t f = 0; f < nf_; ++f) {
      if (!next(&ended)) truncated("face " + std::to_string(f));
      uint64_t n = 0;
      if (!parse_count(tok_, n)) fail("face " + std::to_string(f) + ": corner count '" + shown(tok_) + "' is not a number");
      if (n < 3) fail("face " + std::to_string(f) + " has " + std::to_string(n) + " corners (a face needs at least 3)");
      corners_.clear();
      for (uint64_t i = 0; i < n; ++i) {
        if (!next(&ended)) truncated("face " + std::to_string(f) + " (" + std::to_string(n) + " corners)");
        uint64_t idx = 0;
        if (!parse_count(tok_, idx)) fail("face " + std::to_string(f) + ": corner '" + shown(tok_) + "' is not an index");
        if (idx >= nv_)
          fail("face " + std::to_string(f) + " refers to vertex " + std::to_string(idx) + ", the file has " +
               std::to_string(nv_) + " vertices");
        corners_.push_back(uint32_t(idx));
      }
      if (purpose_ == ReadPurpose::Mesh)
        for (size_t k = 1; k + 1 < corners_.size(); ++k) out.triangles.push_back({corners_[0], corners_[k], corners_[k + 1]});
      if (!ended) {  // a face colour (or a comment)
        face_colours_ = face_colours_ || in_.look_ahead(1) != "#";
        in_.skip_line();
      }
    }
    while (next(&ended))
      fail("more data after the " + std::to_string(nv_) + " vertices and " + std::to_string(nf_) +
           " faces the header declares ('" + shown(tok_) + "'): a count in the header is too small");
    if (extra_vertex_values_)
      note_not_read(out, std::string("vertex colours or texture coordinates (the values after x y z") +
                             (normals_ ? " nx ny nz" : "") + ")");
    if (face_colours_ && purpose_ == ReadPurpose::Mesh) note_not_read(out, "face colours");
    return out;
  }

 private:
  [[noreturn]] void fail(const std::string& problem) const {
    throw Error(Status::FormatError, "'" + in_.path() + "': " + problem);
  }
  [[noreturn]] void truncated(const std::string& where) const {
    fail("truncated: the header promises " + std::to_string(nv_) + " vertices and " + std::to_string(nf_) +
         " faces, the file ends in " + where);
  }
  // The next token that is not in a comment.
  bool next(bool* ended) {
    if (!pending_.empty()) {
      tok_.swap(pending_);
      pending_.clear();
      return true;  // *ended as the keyword's token left it
    }
    while (in_.token(tok_, 256, ended)) {
      if (tok_[0] != '#') return true;
      if (!*ended) in_.skip_line();
    }
    return false;
  }

  FileReader in_;
  ReadPurpose purpose_;
  bool normals_ = false;
  bool extra_vertex_values_ = false, face_colours_ = false;
  uint64_t nv_ = 0, nf_ = 0;
  std::string tok_, pending_;
  std::vector<uint32_t> corners_;
};

}  // namespace

FileContents read_off(const std::string& path, ReadPurpose purpose) { return OffReader(path, purpose).read(); }

}  // namespace particlemesh::detail
