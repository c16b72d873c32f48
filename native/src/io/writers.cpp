// The writers. Hand-written, byte for byte the layout OpenMesh's writers produced (the ones
// we used until they were replaced): OpenMesh's IO is a process-wide singleton whose reader
// and writer modules keep per-call state, so every call had to hold one global lock and
// route its errors through a process-wide stream - not something a library loaded into
// Blender should do. PLY and OBJ are simple enough that the layout is a few lines each.
//
// PLY: an optional comment line (WriteMeshOptions::comment), one vertex element (x y z float32, or float64 when needs_double_positions; nx ny nz
// float32; red green blue uchar from a "color" attribute; every other attribute as float
// properties, "name" or "name_0".."name_k"), one face element (uchar count, int indices; with
// a "uv" corner attribute also MeshLab's uchar count, float texcoord list: u v per corner).
// OBJ: "# V vertices, F faces", then v (with r g b from a "color" attribute) and vn lines
// in turn (float64 positions: every v line, then every vn line), then, with a "uv" corner
// attribute, one vt line per distinct (u, v) in the order first met, then f a//a b//b c//c
// (or f a b c; a/t/a or a/t with texture coordinates). Text values have 9 significant digits
// (what gives a float32 back), 17 for float64 positions.
#include "io/writers.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <unordered_map>

#include "particlemesh/core/error.h"

namespace PM_NAMESPACE::detail {

namespace {

/// Appends numbers as text: the same digits as printf("%.*g") (std::to_chars is specified
/// so), several times faster.
class Text {
 public:
  explicit Text(OutputFile& out) : out_(out), buf_(new char[kSize]), p_(buf_.get()) {}
  ~Text() = default;
  void number(double v, int digits) {
    room(40);
    const auto r = std::to_chars(p_, p_ + 40, v, std::chars_format::general, digits);
    p_ = r.ptr;
  }
  void integer(uint64_t v) {
    room(24);
    p_ = std::to_chars(p_, p_ + 24, v).ptr;
  }
  void put(char c) {
    room(1);
    *p_++ = c;
  }
  void put(std::string_view s) {
    if (s.size() > kSize / 2) {
      flush();
      out_.write(s);
      return;
    }
    room(s.size());
    std::memcpy(p_, s.data(), s.size());
    p_ += s.size();
  }
  /// Room for n bytes (at most the buffer's size), to be filled by the caller.
  char* span(size_t n) {
    room(n);
    char* p = p_;
    p_ += n;
    return p;
  }
  /// Bytes left before the buffer must be flushed.
  size_t space() const { return size_t(buf_.get() + kSize - p_); }
  void flush() {
    out_.write(buf_.get(), size_t(p_ - buf_.get()));
    p_ = buf_.get();
  }

 private:
  // As large as OutputFile's own buffer: a full one goes straight to write(2), not copied
  // into that buffer first.
  static constexpr size_t kSize = size_t(1) << 20;
  void room(size_t n) {
    if (space() < n) flush();
  }
  OutputFile& out_;
  std::unique_ptr<char[]> buf_;
  char* p_;
};

uint8_t color_byte(float c) {
  if (!(c > 0)) return 0;
  if (c >= 1) return 255;
  return uint8_t(std::lround(double(c) * 255.0));
}

/// A PLY property name from an attribute name: letters, digits, '_' (others become '_').
std::string ply_name(const std::string& name) {
  std::string s = name.empty() ? std::string("attribute") : name;
  for (char& c : s)
    if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_')) c = '_';
  return s;
}

/// The "uv" corner attribute when it is one (u, v) per triangle corner, else nullptr.
const VertexAttribute* corner_uv_of(const TriMesh& mesh) {
  for (const VertexAttribute& a : mesh.corner_attributes)
    if (a.name == "uv" && a.components == 2 && a.values.size() == 6 * mesh.triangles.size()) return &a;
  return nullptr;
}

const VertexAttribute* color_of(const TriMesh& mesh) {
  for (const VertexAttribute& a : mesh.attributes)
    if (a.name == "color" && a.components == 3 && a.values.size() == 3 * mesh.positions.size()) return &a;
  return nullptr;
}

}  // namespace

bool needs_double_positions(const std::vector<Vec3>& positions) {
  if (positions.empty()) return false;
  // Four independent running extremes (lanes), merged at the end: min and max are exact, so
  // the result is the serial loop's. Every lane starts from the first point, and a NaN
  // coordinate never replaces a running value (b < a and a < b are false), as in std::min/max.
  constexpr size_t kLanes = 4;
  double lo[3][kLanes], hi[3][kLanes], largest[kLanes], smallest[kLanes];
  for (size_t l = 0; l < kLanes; ++l) {
    for (int a = 0; a < 3; ++a) lo[a][l] = hi[a][l] = positions[0][a];
    largest[l] = 0;
    smallest[l] = DBL_MAX;
  }
  auto take = [&](size_t l, const Vec3& p) {
    for (int a = 0; a < 3; ++a) {
      const double v = p[a];
      lo[a][l] = v < lo[a][l] ? v : lo[a][l];
      hi[a][l] = hi[a][l] < v ? v : hi[a][l];
      const double m = std::abs(v);
      largest[l] = largest[l] < m ? m : largest[l];
      const double pos = m > 0 ? m : DBL_MAX;  // zeros (and NaN) left out
      smallest[l] = pos < smallest[l] ? pos : smallest[l];
    }
  };
  const size_t n = positions.size(), whole = n - n % kLanes;
  for (size_t i = 0; i < whole; i += kLanes)
    for (size_t l = 0; l < kLanes; ++l) take(l, positions[i + l]);
  for (size_t i = whole; i < n; ++i) take(0, positions[i]);
  for (size_t l = 1; l < kLanes; ++l) {
    for (int a = 0; a < 3; ++a) {
      lo[a][0] = std::min(lo[a][0], lo[a][l]);
      hi[a][0] = std::max(hi[a][0], hi[a][l]);
    }
    largest[0] = std::max(largest[0], largest[l]);
    smallest[0] = std::min(smallest[0], smallest[l]);
  }
  const double largest_all = largest[0], smallest_all = smallest[0];
  const Vec3 box_lo{lo[0][0], lo[1][0], lo[2][0]}, box_hi{hi[0][0], hi[1][0], hi[2][0]};
  if (largest_all > FLT_MAX) return true;  // float32 would make it inf
  const double size = norm(box_hi - box_lo);
  // float32 rounds by up to 2^-24 of a value, and by up to 2^-150 below FLT_MIN (subnormals).
  double rounding = largest_all * 0x1p-24;
  if (smallest_all < FLT_MIN) rounding = std::max(rounding, 0x1p-150);
  return rounding > 1e-6 * size;
}

void write_ply(const TriMesh& mesh, OutputFile& out, bool binary, bool normals, const std::string& comment) {
  const auto& P = mesh.positions;
  const auto& N = mesh.normals;
  const bool doubles = needs_double_positions(P);
  const VertexAttribute* color = color_of(mesh);
  std::vector<const VertexAttribute*> extra;
  for (const VertexAttribute& a : mesh.attributes)
    if (&a != color && a.components >= 1 && a.values.size() == P.size() * size_t(a.components)) extra.push_back(&a);

  Text t(out);
  t.put(binary ? "ply\nformat binary_little_endian 1.0\n" : "ply\nformat ascii 1.0\n");
  if (!comment.empty()) {
    t.put("comment ");
    t.put(comment);
    t.put('\n');
  }
  t.put("element vertex ");
  t.integer(P.size());
  t.put(doubles ? "\nproperty double x\nproperty double y\nproperty double z\n"
                : "\nproperty float x\nproperty float y\nproperty float z\n");
  if (normals) t.put("property float nx\nproperty float ny\nproperty float nz\n");
  if (color) t.put("property uchar red\nproperty uchar green\nproperty uchar blue\n");
  // Property names are unique in a PLY element: an attribute whose name is taken (x, red, a
  // second "v", ...) gets a suffix.
  // The reader takes these names in any case as positions, normals and colours (normal_x ..
  // as PCL names normals), so no attribute is written under one of them: "RED" or "normal!y"
  // (written normal_y) would come back as something else.
  std::vector<std::string> used{"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue", "normal_x", "normal_y", "normal_z"};
  auto taken = [&](const std::string& name) {
    for (const std::string& u : used)
      if (u.size() == name.size() && std::equal(u.begin(), u.end(), name.begin(), [](char a, char b) {
            return std::tolower(static_cast<unsigned char>(a)) == std::tolower(static_cast<unsigned char>(b));
          }))
        return true;
    return false;
  };
  for (const VertexAttribute* a : extra) {
    for (int c = 0; c < a->components; ++c) {
      std::string name = ply_name(a->name) + (a->components > 1 ? "_" + std::to_string(c) : std::string());
      while (taken(name)) name += "_";
      used.push_back(name);
      t.put("property float ");
      t.put(name);
      t.put('\n');
    }
  }
  const VertexAttribute* uv = corner_uv_of(mesh);
  t.put("element face ");
  t.integer(mesh.triangles.size());
  t.put("\nproperty list uchar int vertex_indices\n");
  if (uv) t.put("property list uchar float texcoord\n");
  t.put("end_header\n");
  // Binary: little-endian, as the header says (x86-64 and aarch64 hosts are).
  if (binary) {
    // One fixed-size record per vertex (position, normal, color), then the extra attributes;
    // records are filled in place in the output buffer, as many as fit at a time.
    const size_t fixed = (doubles ? 24 : 12) + (normals ? 12 : 0) + (color ? 3 : 0);
    auto record = [&](size_t i, char* rec) {
      size_t k = 0;
      auto f32 = [&](double v) {
        const float f = float(v);
        std::memcpy(rec + k, &f, 4);
        k += 4;
      };
      if (doubles) {
        const double p[3] = {P[i].x, P[i].y, P[i].z};
        std::memcpy(rec, p, 24);
        k = 24;
      } else {
        f32(P[i].x), f32(P[i].y), f32(P[i].z);
      }
      if (normals) f32(N[i].x), f32(N[i].y), f32(N[i].z);
      if (color)
        for (int c = 0; c < 3; ++c) rec[k++] = char(color_byte(color->values[3 * i + size_t(c)]));
    };
    for (size_t i = 0; i < P.size();) {
      if (extra.empty()) {
        const size_t fit = std::min(P.size() - i, t.space() / fixed);
        if (fit == 0) {
          t.flush();
          continue;
        }
        char* r = t.span(fit * fixed);
        if (!doubles && normals && !color) {
          // The common record (what smooth and triangulate write), in a loop of its own.
          for (size_t j = 0; j < fit; ++j) {
            const Vec3 &p = P[i + j], &q = N[i + j];
            const float rec[6] = {float(p.x), float(p.y), float(p.z), float(q.x), float(q.y), float(q.z)};
            std::memcpy(r + j * 24, rec, 24);
          }
        } else {
          for (size_t j = 0; j < fit; ++j) record(i + j, r + j * fixed);
        }
        i += fit;
        continue;
      }
      record(i, t.span(fixed));
      for (const VertexAttribute* a : extra)
        for (int c = 0; c < a->components; ++c) {
          const float f = a->values[i * size_t(a->components) + size_t(c)];
          t.put(std::string_view(reinterpret_cast<const char*>(&f), 4));
        }
      ++i;
    }
    const auto& T = mesh.triangles;
    const size_t face = uv ? 13 + 25 : 13;  // with texture coordinates: a count and 6 floats more
    for (size_t i = 0; i < T.size();) {
      const size_t fit = std::min(T.size() - i, t.space() / face);
      if (fit == 0) {
        t.flush();
        continue;
      }
      char* r = t.span(fit * face);
      for (size_t j = 0; j < fit; ++j, r += face) {
        r[0] = 3;
        std::memcpy(r + 1, T[i + j].data(), 12);
        if (uv) {
          r[13] = 6;
          std::memcpy(r + 14, &uv->values[6 * (i + j)], 24);
        }
      }
      i += fit;
    }
    t.flush();
    return;
  }
  for (size_t i = 0; i < P.size(); ++i) {
    const int digits = doubles ? 17 : 9;
    auto value = [&](double v, bool first) {
      if (!first) t.put(' ');
      t.number(doubles ? v : double(float(v)), digits);
    };
    value(P[i].x, true), value(P[i].y, false), value(P[i].z, false);
    if (normals)
      for (int a = 0; a < 3; ++a) {
        t.put(' ');
        t.number(doubles ? N[i][a] : double(float(N[i][a])), 9);
      }
    if (color)
      for (int c = 0; c < 3; ++c) {
        t.put(' ');
        t.integer(color_byte(color->values[3 * i + size_t(c)]));
      }
    for (const VertexAttribute* a : extra)
      for (int c = 0; c < a->components; ++c) {
        t.put(' ');
        t.number(double(a->values[i * size_t(a->components) + size_t(c)]), 9);
      }
    t.put('\n');
  }
  for (size_t f = 0; f < mesh.triangles.size(); ++f) {
    const Triangle& tri = mesh.triangles[f];
    t.put("3 ");
    t.integer(tri[0]);
    t.put(' ');
    t.integer(tri[1]);
    t.put(' ');
    t.integer(tri[2]);
    if (uv) {
      t.put(" 6");
      for (int c = 0; c < 6; ++c) {
        t.put(' ');
        t.number(double(uv->values[6 * f + size_t(c)]), 9);
      }
    }
    t.put('\n');
  }
  t.flush();
}

void write_obj(const TriMesh& mesh, OutputFile& out, bool normals, const std::string& comment) {
  const auto& P = mesh.positions;
  const auto& N = mesh.normals;
  const bool doubles = needs_double_positions(P);
  const VertexAttribute* color = color_of(mesh);
  Text t(out);
  if (!comment.empty()) {
    t.put("# ");
    t.put(comment);
    t.put('\n');
  }
  t.put("# ");
  t.integer(P.size());
  t.put(" vertices, ");
  t.integer(mesh.triangles.size());
  t.put(" faces\n");
  auto v_line = [&](size_t i) {
    t.put('v');
    for (int a = 0; a < 3; ++a) {
      t.put(' ');
      t.number(doubles ? P[i][a] : double(float(P[i][a])), doubles ? 17 : 9);
    }
    if (color)
      for (int c = 0; c < 3; ++c) {
        t.put(' ');
        t.number(double(color->values[3 * i + size_t(c)]), 9);
      }
    t.put('\n');
  };
  auto vn_line = [&](size_t i) {
    t.put("vn");
    for (int a = 0; a < 3; ++a) {
      t.put(' ');
      t.number(doubles ? N[i][a] : double(float(N[i][a])), 9);
    }
    t.put('\n');
  };
  if (doubles) {  // all v lines, then all vn lines (the float64 layout has always been so)
    for (size_t i = 0; i < P.size(); ++i) v_line(i);
    if (normals)
      for (size_t i = 0; i < P.size(); ++i) vn_line(i);
  } else {  // v and vn in turn, as OpenMesh wrote
    for (size_t i = 0; i < P.size(); ++i) {
      v_line(i);
      if (normals) vn_line(i);
    }
  }
  // Texture coordinates: one vt per distinct (u, v) pair (by its bits), numbered as first met.
  const VertexAttribute* uv = corner_uv_of(mesh);
  std::vector<uint32_t> corner_vt;
  if (uv) {
    std::unordered_map<uint64_t, uint32_t> number;
    corner_vt.resize(3 * mesh.triangles.size());
    for (size_t c = 0; c < corner_vt.size(); ++c) {
      uint32_t bits[2];
      std::memcpy(bits, &uv->values[2 * c], sizeof bits);
      const auto [it, fresh] = number.emplace(uint64_t(bits[0]) << 32 | bits[1], uint32_t(number.size()));
      corner_vt[c] = it->second;
      if (fresh) {
        t.put("vt ");
        t.number(double(uv->values[2 * c]), 9);
        t.put(' ');
        t.number(double(uv->values[2 * c + 1]), 9);
        t.put('\n');
      }
    }
  }
  for (size_t f = 0; f < mesh.triangles.size(); ++f) {
    t.put('f');
    for (size_t c = 0; c < 3; ++c) {
      const uint32_t v = mesh.triangles[f][c];
      t.put(' ');
      t.integer(uint64_t(v) + 1);
      if (uv) {
        t.put('/');
        t.integer(uint64_t(corner_vt[3 * f + c]) + 1);
      }
      if (normals) {
        t.put(uv ? "/" : "//");
        t.integer(uint64_t(v) + 1);
      }
    }
    t.put('\n');
  }
  t.flush();
}

void write_xyz(const PointCloud& cloud, OutputFile& out) {
  Text t(out);
  const bool normals = cloud.has_normals();
  for (size_t i = 0; i < cloud.size(); ++i) {
    for (int a = 0; a < 3; ++a) {
      if (a) t.put(' ');
      t.number(cloud.positions[i][a], 17);
    }
    if (normals)
      for (int a = 0; a < 3; ++a) {
        t.put(' ');
        t.number(cloud.normals[i][a], 9);
      }
    t.put('\n');
  }
  t.flush();
}

}  // namespace particlemesh::detail
