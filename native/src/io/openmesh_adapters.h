// Internal: OpenMesh's importer/exporter interfaces over our flat arrays.
//
// OpenMesh's own mesh kernels refuse non-manifold faces ("complex edge"), which would
// silently drop the seed's raw overlapping triangles. Its reader and writer modules only
// talk to BaseImporter/BaseExporter, so we give them flat arrays directly.
#pragma once

#include <OpenMesh/Core/IO/exporter/BaseExporter.hh>
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>
#include <OpenMesh/Core/Mesh/BaseKernel.hh>

#include <vector>

#include "particlemesh/mesh/tri_mesh.h"

namespace particlemesh::detail {

/// Collects vertices (+ normals if the file has them) and polygons (fanned into triangles).
class FlatImporter final : public OpenMesh::IO::BaseImporter {
 public:
  using VH = OpenMesh::VertexHandle;
  using HH = OpenMesh::HalfedgeHandle;
  using FH = OpenMesh::FaceHandle;
  using EH = OpenMesh::EdgeHandle;

  std::vector<Vec3> positions;
  std::vector<Vec3> normals;
  std::vector<Triangle> triangles;
  std::vector<float> colors;  ///< r g b in [0, 1] per vertex (empty: the file has none)
  bool bad_face = false;  ///< a face referred to a vertex that does not exist

  VH add_vertex(const OpenMesh::Vec3f& p) override { return push(Vec3{p[0], p[1], p[2]}); }
  VH add_vertex(const OpenMesh::Vec3d& p) override { return push(Vec3{p[0], p[1], p[2]}); }
  VH add_vertex() override { return push(Vec3{}); }
  HH add_edge(VH, VH) override { return HH(); }
  FH add_face(const VHandles& idx) override {
    if (idx.size() < 3) return FH();
    for (const auto& h : idx)
      if (h.idx() < 0 || size_t(h.idx()) >= positions.size()) { bad_face = true; return FH(); }
    for (size_t i = 1; i + 1 < idx.size(); ++i)
      triangles.push_back({uint32_t(idx[0].idx()), uint32_t(idx[i].idx()), uint32_t(idx[i + 1].idx())});
    return FH(int(triangles.size() - 1));
  }
  FH add_face(HH) override { return FH(); }
  void add_face_texcoords(FH, VH, const std::vector<OpenMesh::Vec2f>&) override {}
  void add_face_texcoords(FH, VH, const std::vector<OpenMesh::Vec3f>&) override {}
  void set_face_texindex(FH, int) override {}
  void set_point(VH v, const OpenMesh::Vec3f& p) override {
    if (valid(v)) positions[size_t(v.idx())] = Vec3{p[0], p[1], p[2]};
  }
  void set_halfedge(VH, HH) override {}
  void set_normal(VH v, const OpenMesh::Vec3f& n) override { set_n(v, Vec3{n[0], n[1], n[2]}); }
  void set_normal(VH v, const OpenMesh::Vec3d& n) override { set_n(v, Vec3{n[0], n[1], n[2]}); }
  // Vertex colours (OpenMesh's PLY reader delivers red/green/blue of any type as uchar).
  void set_color(VH v, const OpenMesh::Vec3uc& c) override { set_c(v, c[0] / 255.f, c[1] / 255.f, c[2] / 255.f); }
  void set_color(VH v, const OpenMesh::Vec4uc& c) override { set_c(v, c[0] / 255.f, c[1] / 255.f, c[2] / 255.f); }
  void set_color(VH v, const OpenMesh::Vec3f& c) override { set_c(v, c[0], c[1], c[2]); }
  void set_color(VH v, const OpenMesh::Vec4f& c) override { set_c(v, c[0], c[1], c[2]); }
  void set_texcoord(VH, const OpenMesh::Vec2f&) override {}
  void set_status(VH, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_next(HH, HH) override {}
  void set_face(HH, FH) override {}
  void request_face_texcoords2D() override {}
  void set_texcoord(HH, const OpenMesh::Vec2f&) override {}
  void set_texcoord(VH, const OpenMesh::Vec3f&) override {}
  void set_texcoord(HH, const OpenMesh::Vec3f&) override {}
  void set_status(HH, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_color(EH, const OpenMesh::Vec3uc&) override {}
  void set_color(EH, const OpenMesh::Vec4uc&) override {}
  void set_color(EH, const OpenMesh::Vec3f&) override {}
  void set_color(EH, const OpenMesh::Vec4f&) override {}
  void set_status(EH, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_normal(FH, const OpenMesh::Vec3f&) override {}
  void set_normal(FH, const OpenMesh::Vec3d&) override {}
  void set_color(FH, const OpenMesh::Vec3uc&) override {}
  void set_color(FH, const OpenMesh::Vec4uc&) override {}
  void set_color(FH, const OpenMesh::Vec3f&) override {}
  void set_color(FH, const OpenMesh::Vec4f&) override {}
  void set_status(FH, const OpenMesh::Attributes::StatusInfo&) override {}
  void add_texture_information(int, std::string) override {}
  // Deliberately ignore reserve(): header counts are untrusted until the data is read.
  void reserve(unsigned int, unsigned int, unsigned int) override {}
  size_t n_vertices() const override { return positions.size(); }
  size_t n_faces() const override { return triangles.size(); }
  size_t n_edges() const override { return 0; }

 private:
  VH push(const Vec3& p) {
    positions.push_back(p);
    return VH(int(positions.size() - 1));
  }
  bool valid(VH v) const { return v.idx() >= 0 && size_t(v.idx()) < positions.size(); }
  void set_n(VH v, const Vec3& n) {
    if (!valid(v)) return;
    if (normals.size() < positions.size()) normals.resize(positions.size());
    normals[size_t(v.idx())] = n;
  }
  void set_c(VH v, float r, float g, float b) {
    if (!valid(v)) return;
    if (colors.size() < 3 * positions.size()) colors.resize(3 * positions.size());
    float* c = &colors[3 * size_t(v.idx())];
    c[0] = r, c[1] = g, c[2] = b;
  }
};

/// Presents a TriMesh (or a bare point set) to OpenMesh's writers.
class FlatExporter final : public OpenMesh::IO::BaseExporter {
 public:
  using VH = OpenMesh::VertexHandle;
  using HH = OpenMesh::HalfedgeHandle;
  using FH = OpenMesh::FaceHandle;
  using EH = OpenMesh::EdgeHandle;

  FlatExporter(const std::vector<Vec3>& positions, const std::vector<Vec3>& normals,
               const std::vector<Triangle>& triangles, bool with_normals)
      : p_(positions), n_(normals), t_(triangles), with_normals_(with_normals && !normals.empty()) {}

  OpenMesh::Vec3f point(VH v) const override { const Vec3& p = p_[size_t(v.idx())]; return {float(p.x), float(p.y), float(p.z)}; }
  OpenMesh::Vec3d pointd(VH v) const override { const Vec3& p = p_[size_t(v.idx())]; return {p.x, p.y, p.z}; }
  bool is_point_double() const override { return false; }
  OpenMesh::Vec3f normal(VH v) const override {
    if (!with_normals_) return {0, 0, 0};
    const Vec3& n = n_[size_t(v.idx())];
    return {float(n.x), float(n.y), float(n.z)};
  }
  OpenMesh::Vec3d normald(VH v) const override {
    if (!with_normals_) return {0, 0, 0};
    const Vec3& n = n_[size_t(v.idx())];
    return {n.x, n.y, n.z};
  }
  bool is_normal_double() const override { return false; }
  OpenMesh::Vec3uc color(VH) const override { return {0, 0, 0}; }
  OpenMesh::Vec4uc colorA(VH) const override { return {0, 0, 0, 0}; }
  OpenMesh::Vec3ui colori(VH) const override { return {0, 0, 0}; }
  OpenMesh::Vec4ui colorAi(VH) const override { return {0, 0, 0, 0}; }
  OpenMesh::Vec3f colorf(VH) const override { return {0, 0, 0}; }
  OpenMesh::Vec4f colorAf(VH) const override { return {0, 0, 0, 0}; }
  OpenMesh::Vec2f texcoord(VH) const override { return {0, 0}; }
  OpenMesh::Vec2f texcoord(HH) const override { return {0, 0}; }
  OpenMesh::Attributes::StatusInfo status(VH) const override { return {}; }
  unsigned int get_vhandles(FH f, std::vector<VH>& out) const override {
    const Triangle& t = t_[size_t(f.idx())];
    out.assign({VH(int(t[0])), VH(int(t[1])), VH(int(t[2]))});
    return 3;
  }
  HH getHeh(FH, VH) const override { return HH(); }
  unsigned int get_face_texcoords(std::vector<OpenMesh::Vec2f>&) const override { return 0; }
  OpenMesh::Vec3f normal(FH) const override { return {0, 0, 0}; }
  OpenMesh::Vec3d normald(FH) const override { return {0, 0, 0}; }
  OpenMesh::Vec3uc color(FH) const override { return {0, 0, 0}; }
  OpenMesh::Vec4uc colorA(FH) const override { return {0, 0, 0, 0}; }
  OpenMesh::Vec3ui colori(FH) const override { return {0, 0, 0}; }
  OpenMesh::Vec4ui colorAi(FH) const override { return {0, 0, 0, 0}; }
  OpenMesh::Vec3f colorf(FH) const override { return {0, 0, 0}; }
  OpenMesh::Vec4f colorAf(FH) const override { return {0, 0, 0, 0}; }
  OpenMesh::Attributes::StatusInfo status(FH) const override { return {}; }
  OpenMesh::Vec3uc color(EH) const override { return {0, 0, 0}; }
  OpenMesh::Vec4uc colorA(EH) const override { return {0, 0, 0, 0}; }
  OpenMesh::Vec3ui colori(EH) const override { return {0, 0, 0}; }
  OpenMesh::Vec4ui colorAi(EH) const override { return {0, 0, 0, 0}; }
  OpenMesh::Vec3f colorf(EH) const override { return {0, 0, 0}; }
  OpenMesh::Vec4f colorAf(EH) const override { return {0, 0, 0, 0}; }
  OpenMesh::Attributes::StatusInfo status(EH) const override { return {}; }
  int get_halfedge_id(VH) override { return -1; }
  int get_halfedge_id(FH) override { return -1; }
  int get_next_halfedge_id(HH) override { return -1; }
  int get_to_vertex_id(HH) override { return -1; }
  int get_face_id(HH) override { return -1; }
  OpenMesh::Attributes::StatusInfo status(HH) const override { return {}; }
  size_t n_vertices() const override { return p_.size(); }
  size_t n_faces() const override { return t_.size(); }
  size_t n_edges() const override { return 0; }
  bool is_triangle_mesh() const override { return true; }
  bool has_vertex_normals() const override { return with_normals_; }
  // The PLY writer walks the kernel's custom properties; ours has none.
  const OpenMesh::BaseKernel* kernel() override { return &no_properties_; }

 private:
  OpenMesh::BaseKernel no_properties_;
  const std::vector<Vec3>& p_;
  const std::vector<Vec3>& n_;
  const std::vector<Triangle>& t_;
  bool with_normals_;
};

}  // namespace particlemesh::detail
