// Wavefront OBJ meshes: v (x y z, optional w, or x y z r g b), vn, vt, and f with v, v/vt,
// v//vn or v/vt/vn corners (1-based, or negative: relative to the vertices so far); polygons
// are fanned; a line ending in a backslash continues on the next. Texture coordinates become
// the corner attribute "uv" when every face corner names a vt that exists (else they are
// named in not_read, as are materials and l / p elements); other statements (o, g, s,
// usemtl, mtllib, l, p, ...) are skipped.
//
// Also particles (ReadPurpose::Points): the point clouds MeshLab, Blender and CloudCompare
// export are v lines (often v x y z r g b), sometimes one vn per v in the same order, and no
// f. Read for points, the v lines are the particles and faces are skipped (counted only); the
// vn lines are the normals, in order, when the file has no face and exactly one vn per v (for
// a mesh too: a face-less file is a point cloud however it is read), else they only serve the
// faces' corners.
//
// Written by hand, not with tinyobjloader (Debian's libtinyobjloader-dev, 2.0.0rc10), which
// does not fit on three counts, each checked: its number parser is not correctly rounded
// (with TINYOBJLOADER_USE_DOUBLE, 17 161 of 30 000 random 17-digit coordinates came back
// wrong in the last bits, where "coordinates keep their full precision" is a promise here);
// a value it cannot read becomes 0 without a word ("v nan abc 1" reads as 0 0 1, "1.5xyz" as
// 1.5); and a face corner beyond the vertices is only a warning, the face kept with the bad
// index. OpenMesh's OBJ reader kept float32 and asserted on corners without a vertex index.
#include <array>
#include <cfloat>
#include <cmath>
#include <utility>
#include <string>
#include <string_view>
#include <vector>

#include "io/file_reader.h"
#include "io/formats.h"
#include "io/text_numbers.h"
#include "particlemesh/core/error.h"

namespace PM_NAMESPACE::detail {

namespace {

constexpr size_t kMaxLine = size_t(1) << 20;

class ObjReader {
 public:
  ObjReader(const std::string& path, ReadPurpose purpose) : in_(path), purpose_(purpose) {}

  FileContents read() {
    if (in_.peek() < 0) fail_file("the file is empty");
    if (in_.look_ahead(3) == "\xEF\xBB\xBF") in_.skip(3);
    // Read as bytes, UTF-16 text has no statement at all: named instead of an empty mesh.
    if (const std::string_view bom = in_.look_ahead(2); bom == "\xFF\xFE" || bom == "\xFE\xFF")
      fail_file("the file is UTF-16 text (it starts with the byte order mark " +
                std::string(bom[0] == '\xFF' ? "FF FE" : "FE FF") + "): save it as UTF-8 or ASCII text");
    std::string_view line;
    std::vector<std::string_view> w;
    std::string continued;  // a statement whose lines end with a backslash, joined
    auto statement = [&](std::string_view text) {
      split_words(text, w);
      if (w.empty()) return;
      if (w[0] == "v") vertex(w);
      else if (w[0] == "vn") normal(w);
      else if (w[0] == "f") {
        if (purpose_ == ReadPurpose::Mesh) face(w);
        else ++faces_;  // skipped for points; counted (a file with faces has no per-v normals)
      } else if (w[0] == "vt") texture_coordinate(w);
      else if (w[0] == "usemtl") ++materials_;
      else if (w[0] == "l" || w[0] == "p") ++lines_and_points_;
    };
    while (in_.line(line, kMaxLine)) {
      if (const size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
      // A backslash ending a line continues the statement on the next one (the OBJ
      // specification's line continuation; exporters use it to wrap long faces).
      const size_t last = line.find_last_not_of(" \t\r");
      if (last != std::string_view::npos && line[last] == '\\') {
        continued.append(line.substr(0, last)).push_back(' ');
        if (continued.size() > kMaxLine) fail("a statement continued over lines is longer than " + std::to_string(kMaxLine) + " bytes");
        continue;
      }
      if (continued.empty()) {
        statement(line);
        continue;
      }
      continued.append(line);
      statement(continued);
      continued.clear();
    }
    if (!continued.empty()) statement(continued);  // the file ended on a continued line
    FileContents out;
    out.positions = std::move(positions_);
    out.triangles = std::move(triangles_);
    out.faces = faces_;
    if (faces_ == 0 && !normals_.empty() && normals_.size() == out.positions.size()) {
      // A point cloud's normals: one vn per v, in order (a count that differs says nothing
      // about which normal is whose, so they are ignored then).
      out.normals = std::move(normals_);
    } else if (any_vertex_normal_) {
      // One normal per vertex from the corners that name one (the last wins, as OpenMesh's
      // reader did); a vertex no corner gives a normal keeps (0, 0, 0): no normal.
      vertex_normals_.resize(out.positions.size());
      out.normals = std::move(vertex_normals_);
    }
    if (colored_ == out.positions.size() && colored_ > 0) out.attributes.push_back({"color", 3, std::move(colors_)});
    // Said rather than dropped silently: what a mesh read here does not carry.
    if (colored_ > 0 && colored_ < out.positions.size())
      note_not_read(out, "vertex colours (" + std::to_string(colored_) + " of the " + std::to_string(out.positions.size()) +
                             " vertices have one: a channel needs every vertex's)");
    if (purpose_ == ReadPurpose::Mesh) {
      const uint64_t vt = texture_coordinates_;
      if (vt > 0 && faces_ > 0 && corners_without_uv_ == 0 && uv_out_of_range_.empty()) {
        out.corner_attributes.push_back({"uv", 2, std::move(corner_uvs_)});
      } else if (vt > 0 && faces_ > 0) {
        const std::string why = !uv_out_of_range_.empty()
                                    ? "a face names " + uv_out_of_range_
                                    : corners_without_uv_ == 1 ? std::string("1 face corner names none")
                                                               : std::to_string(corners_without_uv_) + " face corners name none";
        note_not_read(out, "texture coordinates (" + std::to_string(vt) + " vt; " + why + ")");
      }
      if (materials_ > 0) note_not_read(out, "materials (" + std::to_string(materials_) + " usemtl)");
      if (lines_and_points_ > 0)
        note_not_read(out, "line and point elements (" + std::to_string(lines_and_points_) + " l / p)");
    }
    return out;
  }

 private:
  [[noreturn]] void fail_file(const std::string& problem) const {
    throw Error(Status::FormatError, "'" + in_.path() + "': " + problem);
  }
  [[noreturn]] void fail(const std::string& problem) const {
    fail_file("line " + std::to_string(in_.line_number()) + ": " + problem);
  }

  double number(std::string_view t, const char* what) const {
    double v = 0;
    switch (parse_number(t, v)) {
      case NumberText::Ok: break;
      case NumberText::NotANumber: fail(std::string(what) + " '" + shown(t) + "' is not a number");
      case NumberText::Overflow: fail(std::string(what) + " '" + shown(t) + "' is beyond the range of double (1.8e308)");
    }
    if (std::isnan(v)) fail(std::string(what) + " is NaN ('" + shown(t) + "')");
    return v;
  }

  void vertex(const std::vector<std::string_view>& w) {
    // v x y z, v x y z w, v x y z r g b (the colour extension MeshLab and others write).
    const size_t n = w.size() - 1;
    if (n != 3 && n != 4 && n != 6)
      fail("'v' with " + std::to_string(n) + " values (expected x y z, x y z w, or x y z r g b)");
    static const char* const kWhat[3] = {"vertex x", "vertex y", "vertex z"};
    positions_.push_back({number(w[1], kWhat[0]), number(w[2], kWhat[1]), number(w[3], kWhat[2])});
    if (n == 6) {
      colors_.resize(3 * positions_.size(), 0.0f);
      for (int k = 0; k < 3; ++k) colors_[3 * (positions_.size() - 1) + size_t(k)] = float(number(w[size_t(4 + k)], "colour"));
      ++colored_;
    }
  }

  void texture_coordinate(const std::vector<std::string_view>& w) {
    ++texture_coordinates_;
    if (purpose_ != ReadPurpose::Mesh) return;
    // vt u, vt u v or vt u v w; 3D texture coordinates keep u and v.
    if (w.size() < 2 || w.size() > 4) fail("'vt' with " + std::to_string(w.size() - 1) + " values (expected u, u v or u v w)");
    const double u = number(w[1], "texture u"), v = w.size() > 2 ? number(w[2], "texture v") : 0.0;
    for (const auto& [x, text] : {std::pair{u, w[1]}, std::pair{v, w.size() > 2 ? w[2] : w[1]}})
      if (std::abs(x) > double(FLT_MAX))
        fail("texture coordinate '" + shown(text) + "' is beyond the range of float (3.4e38)");
    uvs_.push_back({u, v});
  }

  void normal(const std::vector<std::string_view>& w) {
    if (w.size() != 4) fail("'vn' with " + std::to_string(w.size() - 1) + " values (expected 3)");
    normals_.push_back({number(w[1], "normal x"), number(w[2], "normal y"), number(w[3], "normal z")});
  }

  // One index of a corner: 1-based, or negative (relative to the `count` defined so far).
  bool index(std::string_view s, size_t count, uint32_t& out, bool* empty) const {
    if (s.empty()) {
      if (!empty) return false;
      *empty = true;
      return true;
    }
    int64_t v = 0;
    if (!parse_integer(s, v) || v == 0) return false;
    if (v < 0) v += int64_t(count) + 1;
    if (v < 1) return false;
    if (v > int64_t(UINT32_MAX) - 1) return false;
    out = uint32_t(v - 1);
    return true;
  }

  // An index that is not looked up (a texture coordinate's; a normal's in a file without
  // 'vn'): any non-zero integer, negative too, or none.
  static bool unused_index(std::string_view s) {
    int64_t v = 0;
    return s.empty() || (parse_integer(s, v) && v != 0);
  }

  void face(const std::vector<std::string_view>& w) {
    ++faces_;
    const size_t n = w.size() - 1;
    if (n < 3) fail("a face with " + std::to_string(n) + " corner" + (n == 1 ? "" : "s") + " (at least 3)");
    corners_.clear();
    corner_uv_.clear();
    for (size_t i = 1; i < w.size(); ++i) {
      const std::string_view c = w[i];
      const size_t a = c.find('/');
      uint32_t v = 0, vn = 0, vt = kNoUv;
      bool ok = index(c.substr(0, a), positions_.size(), v, nullptr), has_vn = false;
      if (ok && a != std::string_view::npos) {
        const std::string_view rest = c.substr(a + 1);
        const size_t b = rest.find('/');
        // The texture coordinate (-1: the last 'vt'). One that names no vt is not an
        // error (the coordinates are then not read, and said so); in a file without vt
        // lines it is a placeholder.
        const std::string_view vt_text = rest.substr(0, b);
        ok = unused_index(vt_text);
        bool no_vt = vt_text.empty();
        if (ok && !no_vt && !uvs_.empty()) {
          if (!index(vt_text, uvs_.size(), vt, nullptr) || vt >= uvs_.size()) {
            if (uv_out_of_range_.empty())
              uv_out_of_range_ = "vt " + std::string(vt_text) + " of " + std::to_string(uvs_.size());
            vt = kNoUv;
          }
        }
        if (ok && b != std::string_view::npos) {
          bool no_vn = false;
          const std::string_view vn_text = rest.substr(b + 1);
          if (normals_.empty()) {
            // Normal indices in a file with no 'vn' at all (placeholders some tools write;
            // tinyobjloader and trimesh read such files) are ignored: the normals are then
            // estimated.
            ok = unused_index(vn_text);
          } else {
            ok = index(vn_text, normals_.size(), vn, &no_vn) && vn_text.find('/') == std::string_view::npos;
            has_vn = ok && !no_vn;
          }
        }
      }
      if (!ok)
        fail("face corner '" + shown(c) + "' is not v, v/vt, v//vn or v/vt/vn with integer indices" +
             " (1-based, or negative counting back from the last)");
      if (v >= positions_.size())
        fail("face corner '" + shown(c) + "' names vertex " + std::to_string(uint64_t(v) + 1) + ", but only " +
             std::to_string(positions_.size()) + " are defined so far");
      if (has_vn) {
        if (vn >= normals_.size())
          fail("face corner '" + shown(c) + "' names normal " + std::to_string(vn + 1) + ", but only " +
               std::to_string(normals_.size()) + " are defined so far");
        if (vertex_normals_.size() <= v) vertex_normals_.resize(size_t(v) + 1);
        vertex_normals_[v] = normals_[vn];
        any_vertex_normal_ = true;
      }
      corners_.push_back(v);
      corner_uv_.push_back(vt);
      if (vt == kNoUv) ++corners_without_uv_;
    }
    for (size_t k = 1; k + 1 < corners_.size(); ++k) {
      triangles_.push_back({corners_[0], corners_[k], corners_[k + 1]});
      if (corners_without_uv_ == 0 && uv_out_of_range_.empty())
        for (const size_t j : {size_t(0), k, k + 1})
          for (int d = 0; d < 2; ++d) corner_uvs_.push_back(float(uvs_[corner_uv_[j]][size_t(d)]));
    }
  }

  FileReader in_;
  ReadPurpose purpose_;
  std::vector<Vec3> positions_, normals_, vertex_normals_;
  std::vector<float> colors_;
  size_t colored_ = 0;
  uint64_t texture_coordinates_ = 0, materials_ = 0, lines_and_points_ = 0;
  bool any_vertex_normal_ = false;
  std::vector<Triangle> triangles_;
  std::vector<uint32_t> corners_, corner_uv_;  // a face's vertices and vt indices
  static constexpr uint32_t kNoUv = UINT32_MAX;
  std::vector<std::array<double, 2>> uvs_;     // the vt lines' u v
  std::vector<float> corner_uvs_;              // 6 per triangle while every corner has a vt
  uint64_t corners_without_uv_ = 0;
  std::string uv_out_of_range_;                // the first vt index beyond the vt lines
  uint64_t faces_ = 0;
};

}  // namespace

FileContents read_obj(const std::string& path, ReadPurpose purpose) { return ObjReader(path, purpose).read(); }

}  // namespace particlemesh::detail
