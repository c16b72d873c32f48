// pm_fuzz_seeds OUT [SHARED_DATA]: the seed corpus of every fuzz target, made at run time:
// small files written by particlemesh's own writers, hand-made files for the corners of each
// format (comments, lists, other types, endianness, quads, negative indices, OFF/STL), byte
// strings for the C ABI targets, and the small files of the shared data folder (copied into
// OUT, never into the repository). OUT/<target>/ gets one file per seed.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <tuple>
#include <vector>

#include <zlib.h>

#include "particlemesh/io/mesh_io.h"
#include "particlemesh/io/png.h"
#include "particlemesh/sample/shapes.h"
#include "support/compressed_vtu.h"
#include "support/houdini_scf.h"

namespace fs = std::filesystem;
using namespace particlemesh;

namespace {

fs::path g_out;

void put(const std::string& target, const std::string& name, const std::string& bytes) {
  const fs::path dir = g_out / target;
  fs::create_directories(dir);
  std::ofstream(dir / name, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// Write with our writers into a scratch file and return its bytes.
std::string via_mesh_writer(const TriMesh& m, const std::string& ext, MeshFormat f = MeshFormat::Auto) {
  const fs::path p = g_out / (".scratch" + ext);
  write_mesh(m, p.string(), {f, true});
  std::string b = slurp(p);
  fs::remove(p);
  return b;
}
std::string via_cloud_writer(const PointCloud& c, const std::string& ext) {
  const fs::path p = g_out / (".scratch" + ext);
  write_point_cloud(c, p.string());
  std::string b = slurp(p);
  fs::remove(p);
  return b;
}

template <class T>
void append(std::string& s, T v) {
  s.append(reinterpret_cast<const char*>(&v), sizeof v);
}

// Big-endian values, as bgeo stores them.
void append_be32(std::string& s, uint32_t v) {
  for (int k = 3; k >= 0; --k) s += char((v >> (8 * k)) & 0xff);
}
void append_be_float(std::string& s, float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  append_be32(s, u);
}
void append_be16(std::string& s, uint16_t v) {
  s += char(v >> 8);
  s += char(v & 0xff);
}

/// Houdini 12+'s binary JSON (little-endian) of `points` points: P paged in [1, 2] sub-vectors
/// with a constant page, a scalar as "arrays", a vector as "tuples", a string attribute, an
/// info map, token-defined and plain strings.
std::string bgeo_json_seed(int points) {
  std::string s = "\x7fNSJb";
  int next_token = 0;
  auto str = [&](const std::string& t, bool token = true) {
    if (token) {
      s += char(0x2b);
      s += char(next_token);
      s += char(t.size());
      s += t;
      s += char(0x26);
      s += char(next_token++);
    } else {
      s += char(0x27);
      s += char(t.size());
      s += t;
    }
  };
  auto i32 = [&](int32_t v) {
    s += char(0x13);
    append(s, v);
  };
  auto floats = [&](const std::vector<float>& v) {
    s += char(0x40);
    s += char(0x19);
    s += char(v.size());
    for (float f : v) append(s, f);
  };
  const int page = 4, pages = (points + page - 1) / page;
  s += '[';
  str("fileversion"), str("19.5.303", false), str("pointcount"), i32(points);
  str("info"), s += '{', str("software", false), str("seed", false), s += '}';
  str("attributes"), s += '[', str("pointattributes"), s += '[';
  // P: x varies; (y, z) constant on page 0.
  s += '[', s += '[', str("name"), str("P"), str("type"), str("numeric"), s += ']';
  s += '[', str("size"), i32(3), str("values"), s += '[', str("size"), i32(3), str("packing"), s += '[', i32(1), i32(2),
      s += ']', str("pagesize"), i32(page), str("constantpageflags"), s += '[';
  s += char(0x40), s += char(0x10), s += char(pages), append(s, uint32_t(0));
  s += char(0x40), s += char(0x10), s += char(pages), append(s, uint32_t(1));
  s += ']', str("rawpagedata");
  std::vector<float> raw;
  for (int pg = 0; pg < pages; ++pg) {
    const int m = std::min(page, points - pg * page);
    for (int e = 0; e < m; ++e) raw.push_back(float(pg * page + e) * 0.1f);
    if (pg == 0) {
      raw.push_back(0.5f), raw.push_back(0.25f);
    } else {
      for (int e = 0; e < m; ++e) raw.push_back(float(e) * 0.05f), raw.push_back(float(pg) * 0.2f);
    }
  }
  floats(raw);
  s += ']', s += ']', s += ']';
  // density: "arrays"; N: "tuples".
  s += '[', s += '[', str("name"), str("density"), str("type"), str("numeric"), s += ']';
  s += '[', str("size"), i32(1), str("values"), s += '[', str("size"), i32(1), str("arrays"), s += '[';
  std::vector<float> density;
  for (int i = 0; i < points; ++i) density.push_back(1000.0f + float(i));
  floats(density);
  s += ']', s += ']', s += ']', s += ']';
  s += '[', s += '[', str("name"), str("N"), str("type"), str("numeric"), s += ']';
  s += '[', str("size"), i32(3), str("values"), s += '[', str("size"), i32(3), str("tuples"), s += '[';
  for (int i = 0; i < points; ++i) floats({0.0f, 0.0f, 1.0f});
  s += ']', s += ']', s += ']', s += ']';
  s += '[', s += '[', str("name"), str("kind"), str("type"), str("string"), s += ']';
  s += '[', str("size"), i32(1), str("strings"), s += '[', str("water", false), s += ']', s += ']', s += ']';
  s += ']', s += ']', s += ']';
  return s;
}

/// A classic bgeo ("BgeoV" 5) of `points` points with a float, an int, a vector "N" and an
/// index (string) attribute; `primitive`: one particle-system primitive listing them.
std::string bgeo_seed(int points, bool primitive) {
  std::string s = "BgeoV";
  for (int v : {5, points, primitive ? 1 : 0, 0, 0, 4, 0, 0, 0}) append_be32(s, uint32_t(v));
  auto define = [&](const std::string& name, uint16_t size, int type) {
    append_be16(s, uint16_t(name.size()));
    s += name;
    append_be16(s, size);
    append_be32(s, uint32_t(type));
    if (type == 4) {
      append_be32(s, 2);
      for (const char* str : {"water", "foam"}) {
        append_be16(s, uint16_t(std::strlen(str)));
        s += str;
      }
    } else {
      for (int k = 0; k < size; ++k) append_be32(s, 0);
    }
  };
  define("density", 1, 0);
  define("id", 1, 1);
  define("N", 3, 5);
  define("kind", 1, 4);
  for (int i = 0; i < points; ++i) {
    for (float v : {float(i), float(i % 2), 0.5f, 1.0f}) append_be_float(s, v);
    append_be_float(s, 1000.0f + float(i));
    append_be32(s, uint32_t(i));
    for (float v : {0.0f, 0.0f, 1.0f}) append_be_float(s, v);
    append_be32(s, uint32_t(i % 2));
  }
  if (primitive) {
    append_be32(s, 0x8000);
    append_be32(s, uint32_t(points));
    for (int i = 0; i < points; ++i) append_be16(s, uint16_t(i));
  }
  s += '\0';
  s += char(0xff);
  return s;
}

void file_seeds() {
  const PointCloud sphere = fibonacci_sphere(40);
  PointCloud bare = sphere;
  bare.normals.clear();
  const TriMesh ico = icosphere_mesh(1);
  const TriMesh torus = torus_mesh(1.0, 0.4, 8, 6);

  // PLY: our binary and ASCII writers, then hand-made corners.
  put("read_ply", "sphere_normals_binary.ply", via_cloud_writer(sphere, ".ply"));
  put("read_ply", "ico_binary.ply", via_mesh_writer(ico, ".ply"));
  put("read_ply", "torus_ascii.ply", via_mesh_writer(torus, ".ply", MeshFormat::PlyAscii));
  TriMesh textured = ico;  // MeshLab's texcoord face lists
  textured.corner_attributes = {{"uv", 2, {}}};
  for (size_t i = 0; i < 6 * ico.triangles.size(); ++i) textured.corner_attributes[0].values.push_back(float(i % 7) / 7);
  put("read_ply", "ico_texcoord_binary.ply", via_mesh_writer(textured, ".ply"));
  put("read_ply", "ico_texcoord_ascii.ply", via_mesh_writer(textured, ".ply", MeshFormat::PlyAscii));
  put("read_ply", "points_ascii_double.ply",
      "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 4\nproperty double x\nproperty double y\n"
      "property double z\nproperty uchar red\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0 255\n1 0 0 0\n0 1 0 7\n1 1 0.5 9\n3 0 1 2\n4 1 3 2 0\n");
  put("read_ply", "normals_ascii.ply",
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "property float nx\nproperty float ny\nproperty float nz\nend_header\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n");
  put("read_ply", "pcl_normals_vectors_ascii.ply",
      "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
      "property float normal_x\nproperty float normal_y\nproperty float normal_z\nproperty float curvature\n"
      "property float vx\nproperty float vy\nproperty float vz\nproperty float a.x\nproperty float a.y\n"
      "end_header\n0 0 0 0 0 1 0.5 1 2 3 4 5\n1 0 0 0 1 0 0.25 -1 -2 -3 -4 -5\n");
  {
    std::string be = "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                     "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    const float v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    for (float f : v) {
      uint32_t u;
      std::memcpy(&u, &f, 4);
      u = __builtin_bswap32(u);
      append(be, u);
    }
    be += char(3);
    for (uint32_t i : {0u, 1u, 2u}) append(be, __builtin_bswap32(i));
    put("read_ply", "tri_big_endian.ply", be);
  }

  // The reader's own paths: a list inside the vertex element, faces before vertices, colours
  // and other properties (attributes), upper-case names, doubles beyond float32.
  put("read_ply", "list_in_vertex_faces_first.ply",
      "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_indices\nelement vertex 3\n"
      "property float X\nproperty list uchar int ids\nproperty float Y\nproperty float Z\nproperty uchar red\n"
      "property uchar green\nproperty uchar blue\nproperty float density\nend_header\n3 0 1 2\n"
      "0 2 4 5 0 0 255 0 0 1.5\n1 0 0 0 0 255 0 2\n0 1 7 1 0 0 0 255 3\n");
  {
    std::string d = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
                    "property double z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    for (double v : {4e38, 0.0, 0.0, 5e38, 0.0, 0.0, 1e-300, 1e38, 0.0}) append(d, v);
    d += char(3);
    for (int32_t i : {0, 1, 2}) append(d, i);
    put("read_ply", "doubles_beyond_float.ply", d);
  }
  // bgeo: our own layouts (the shared data adds gzip-compressed ones).
  put("read_bgeo", "points_attributes.bgeo", bgeo_seed(5, false));
  put("read_bgeo", "particle_system.bgeo", bgeo_seed(4, true));
  put("read_bgeo", "binary_json.bgeo", bgeo_json_seed(10));
  put("read_bgeo", "classic_ascii.geo",
      "PGEOMETRY V5\nNPoints 3 NPrims 0\nNPointGroups 0 NPrimGroups 0\n"
      "NPointAttrib 3 NVertexAttrib 0 NPrimAttrib 0 NAttrib 0\nPointAttrib\nv 3 vector 0 0 0\nid 1 int 0\n"
      "name 1 index 2 a b\n0 0 0 1 (1 2 3 7 0)\n1 0 0 1 (4 5 6 8 1)\n0 1 0 1 (7 8 9 9 0)\nbeginExtra\nendExtra\n");
  // Houdini's .bgeo.sc: Blosc chunks of 64 bytes (several per file) in the SCF container.
  put("read_bgeo", "blosc_lz4.bgeo.sc", test::scf_wrap(bgeo_json_seed(10), 64, "lz4"));
  put("read_bgeo", "blosc_zstd_classic.bgeo.sc", test::scf_wrap(bgeo_seed(5, false), 64, "zstd", "{}"));
  {
    // Krakatoa .prt: Position float32[3], Velocity float16[3], Density float64 over 4 particles.
    std::string prt("\xC0PRT\r\n\x1A\n", 8);
    append(prt, int32_t(56));
    prt += std::string("Extensible Particle Format") + std::string(6, '\0');
    append(prt, int32_t(1));
    append(prt, int64_t(4));
    for (int32_t v : {4, 3, 44}) append(prt, v);
    int32_t offset = 0;
    for (const auto& [name, type, arity, size] : {std::tuple{"Position", 4, 3, 12}, std::tuple{"Velocity", 3, 3, 6},
                                                  std::tuple{"Density", 5, 1, 8}}) {
      prt += std::string(name) + std::string(32 - std::strlen(name), '\0');
      for (int32_t v : {type, arity, offset}) append(prt, v);
      offset += size;
    }
    std::string records;
    for (int i = 0; i < 4; ++i) {
      for (float v : {float(i), float(i % 2), 0.5f}) append(records, v);
      for (uint16_t h : {uint16_t(0x3c00), uint16_t(0), uint16_t(0xbc00)}) append(records, h);
      append(records, 1000.0 + i);
    }
    uLongf size = compressBound(uLong(records.size()));
    std::string z(size, '\0');
    compress(reinterpret_cast<Bytef*>(z.data()), &size, reinterpret_cast<const Bytef*>(records.data()), uLong(records.size()));
    put("read_prt", "krakatoa.prt", prt + z.substr(0, size));
  }
  {
    // ASPRS LAS 1.2, point format 2 (colour), four points, a scale of 1/1000.
    std::string las(227, '\0');
    las.replace(0, 4, "LASF");
    las[24] = 1, las[25] = 2;
    auto put_at = [&](size_t at, auto v) { std::memcpy(las.data() + at, &v, sizeof v); };
    put_at(94, uint16_t(227));
    put_at(96, uint32_t(227));
    las[104] = 2;
    put_at(105, uint16_t(26));
    put_at(107, uint32_t(4));
    for (size_t a = 0; a < 3; ++a) put_at(131 + 8 * a, 0.001);
    for (int i = 0; i < 4; ++i) {
      for (int32_t c : {1000 * i, 1000 * (i % 2), 500}) append(las, c);
      append(las, uint16_t(100 * i));
      for (uint8_t b : {uint8_t(0), uint8_t(2), uint8_t(0), uint8_t(0)}) las += char(b);
      append(las, uint16_t(0));
      for (uint16_t c : {uint16_t(65535), uint16_t(0), uint16_t(30000)}) append(las, c);
    }
    put("read_las", "format2.las", las);
  }
  put("read_bgeo", "ascii.geo",
      "[\"pointcount\",3,\"info\",{\"a\\u00e9\":\"x\\n\"},\"attributes\",[\"pointattributes\",[[[\"name\",\"P\","
      "\"type\",\"numeric\"],[\"size\",3,\"values\",[\"size\",3,\"packing\",[1,2],\"pagesize\",2,"
      "\"constantpageflags\",[[false,true],[]],\"rawpagedata\",[0.5,-1e-3,1,2,3,4,5,6,7]]]],[[\"name\",\"v\","
      "\"type\",\"numeric\"],[\"size\",1,\"values\",[\"size\",1,\"tuples\",[[1],[2],[3]]]]]]]]");
  // VTK: the first byte picks the format (0 .vtk, 1 .vtu, 2 .vtp); our writers' files, then
  // hand-made ASCII ones with POINT_DATA and inline XML arrays.
  put("read_vtk", "ico.vtk", std::string(1, '\0') + via_mesh_writer(ico, ".vtk"));
  put("read_vtk", "ico.vtu", std::string(1, '\1') + via_mesh_writer(ico, ".vtu"));
  put("read_vtk", "torus.vtp", std::string(1, '\2') + via_mesh_writer(torus, ".vtp"));
  put("read_vtk", "points_ascii.vtk",
      std::string(1, '\0') +
          "# vtk DataFile Version 3.0\nparticles\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS 3 double\n0 0 0 1 0 0 0 1 "
          "0\nCELLS 0 0\nCELL_TYPES 0\nPOINT_DATA 3\nVECTORS velocity float\n1 0 0 0 1 0 0 0 1\nSCALARS density "
          "float 1\nLOOKUP_TABLE default\n1000 1001 1002\nFIELD FieldData 1\nid 1 3 int\n7 8 9\nNORMALS n float\n0 0 "
          "1 0 0 1 0 0 1\n");
  put("read_vtk", "points_ascii.vtu",
      std::string(1, '\1') +
          "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
          "header_type=\"UInt64\">\n<UnstructuredGrid><Piece NumberOfPoints=\"3\" NumberOfCells=\"0\"><PointData>"
          "<DataArray type=\"Float64\" Name=\"density\" format=\"ascii\">1 2 3</DataArray><DataArray type=\"Int32\" "
          "Name=\"id\" format=\"ascii\">4 5 6</DataArray></PointData><Points><DataArray type=\"Float32\" "
          "NumberOfComponents=\"3\" format=\"ascii\">0 0 0 1 0 0 0 1 0</DataArray></Points><Cells><DataArray "
          "type=\"Int64\" Name=\"connectivity\" format=\"ascii\"></DataArray><DataArray type=\"Int64\" "
          "Name=\"offsets\" format=\"ascii\"></DataArray><DataArray type=\"UInt8\" Name=\"types\" "
          "format=\"ascii\"></DataArray></Cells></Piece></UnstructuredGrid>\n</VTKFile>\n");
  {
    // Positions compressed by each of VTK's compressors, in blocks of 40 bytes (the last short).
    std::vector<float> xyz;
    for (int i = 0; i < 3 * 9; ++i) xyz.push_back(float(i) * 0.25f);
    put("read_vtk", "zlib.vtu", std::string(1, '\1') + test::compressed_vtu(test::VtuCodec::Zlib, xyz, 40));
    put("read_vtk", "lz4.vtu", std::string(1, '\1') + test::compressed_vtu(test::VtuCodec::Lz4, xyz, 40));
    put("read_vtk", "lzma.vtu", std::string(1, '\1') + test::compressed_vtu(test::VtuCodec::Xz, xyz, 40));
  }
  // A parallel file: its pieces do not exist beside the fuzzer's input, so the list itself is
  // what is exercised (sources, the folder rule, the refusals).
  put("read_vtk", "parallel.vtu",
      std::string(1, '\1') +
          "<?xml version=\"1.0\"?>\n<VTKFile type=\"PUnstructuredGrid\" version=\"0.1\"><PUnstructuredGrid>"
          "<PPoints><PDataArray type=\"Float32\" NumberOfComponents=\"3\"/></PPoints><Piece Source=\"p/p_0.vtu\"/>"
          "<Piece Source=\"../p_1.vtu\"/></PUnstructuredGrid></VTKFile>\n");
  // Collections (the first byte 250 on: .pvd even, .series odd).
  put("read_vtk", "collection.pvd",
      std::string(1, char(250)) +
          "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\"><Collection>"
          "<DataSet timestep=\"0.5\" part=\"0\" file=\"f_1.vtu\"/><DataSet timestep=\"0\" file=\"d\\f_0.vtu\"/>"
          "</Collection></VTKFile>\n");
  put("read_vtk", "collection.series",
      std::string(1, char(251)) +
          "{\"file-series-version\": \"1.0\", \"files\": [{\"name\": \"f_0.vtu\", \"time\": 0},"
          " {\"name\": \"d/f_1.vtu\", \"time\": 1.5e-3}]}");
  put("read_xyz", "bom.xyz", "\xEF\xBB\xBF" "0 0 0\n1 0 0\n0 1 0\n");
  // Columns named by a header line, and told from their count (colours, intensity, normals).
  put("read_xyz", "header.xyz", "//X,Y,Z,R,G,B,Intensity,Nx,Ny,Nz\n0,0,0,255,0,0,5,0,0,1\n1,0,0,0,255,0,6,0,0,1\n");
  put("read_xyz", "paraview_csv.xyz",
      "\"Velocity:0\",\"Velocity:1\",\"Velocity:2\",\"Point ID\",\"Points:0\",\"Points:1\",\"Points:2\"\n"
      "1,2,3,0,0,0,0\n4,5,6,1,1,0,0\n7,8,9,2,0,1,0\n");
  put("read_xyz", "pandas_csv.xyz", ",x,y,z,vx,vy,vz,Pos.x,Pos.y,Pos.z,n_0,n_1,n_2\n0,0,0,0,1,1,1,0,0,0,0,0,1\n");
  put("read_xyz", "rgb_intensity.xyz", "0 0 0 255 0 0 9\n1 0 0 0 255 0 8\n0 1 0 0 0 255 7\n");
  put("read_xyz", "colour_normal.xyz", "0 0 0 255 0 0 0 0 1\n1 0 0 0 255 0 0 1 0\n");
  put("read_obj", "uv_seam.obj",
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1 0\nvt 0 1\nvn 0 0 1\n"
      "f 1/1/1 2/2/1 3/-2/1 4/4/1\nf 2/4 1/3 3\n");
  put("read_obj", "colours.obj", "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 1\nvn 0 0 1\nf 1//1 2//1 3//1\n");
  put("read_obj", "stl_two_solids.bin",
      "\xFE" "solid\nfacet normal 0 0 1\n outer loop\n vertex 0 0 0\n vertex 1 0 0\n vertex 0 1 0\n endloop\nendfacet\n"
      "endsolid\nsolid b\nfacet normal 0 0 1\n outer loop\n vertex 1 0 0\n vertex 1 1 0\n vertex 0 1 0\n endloop\n"
      "endfacet\nendsolid b\n");

  // OBJ (and OFF / STL behind their marker byte, see fuzz_read_obj.cpp).
  put("read_obj", "ico.obj", via_mesh_writer(ico, ".obj"));
  put("read_obj", "quads_negative_uv.obj",
      "# made by hand\nmtllib none.mtl\no quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\n"
      "vn 0 0 1\ng g1\nusemtl m\ns 1\nf 1/1/1 2/2/1 3/3/1 4/1/1\nf -4 -2 -1\nf 1//1 3//1 4//1\nl 1 2\n");
  put("read_obj", "off.bin", "\xFF" "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n4 1 3 2 0\n");
  put("read_obj", "off_colors.bin", "\xFF" "COFF\n3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n3 0 1 2\n");
  put("read_obj", "stl_ascii.bin",
      "\xFE" "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\n"
      "endfacet\nendsolid t\n");
  {
    std::string stl = "\xFE";
    stl += std::string(80, ' ');
    append(stl, uint32_t(2));
    const float tri[2][12] = {{0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0}, {0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1, 0}};
    for (const auto& t : tri) {
      for (float f : t) append(stl, f);
      append(stl, uint16_t(0));
    }
    put("read_obj", "stl_binary.bin", stl);
  }

  // PNG: our writer's files.
  for (int size : {1, 7, 40}) {
    Image img;
    img.width = size;
    img.height = size + 1;
    for (int i = 0; i < img.width * img.height * 3; ++i) img.rgb.push_back(uint8_t(i * 37));
    const fs::path p = g_out / ".scratch.png";
    write_png(img, p.string());
    put("read_png", "rgb_" + std::to_string(size) + ".png", slurp(p));
    fs::remove(p);
  }

  // XYZ.
  put("read_xyz", "sphere_normals.xyz", via_cloud_writer(sphere, ".xyz"));
  put("read_xyz", "sphere.xyz", via_cloud_writer(bare, ".xyz"));
  put("read_xyz", "corners.xyz", "# comment\n0 0 0\n\n1,0,0\n+0.5 1e-3 -2 # trailing\n\t3 4 5\r\n1e308 0 0\n");

  // PCD: ascii and binary made here (the compressed ones come from the shared data).
  put("read_pcd", "ascii.pcd",
      "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\n"
      "COUNT 1 1 1 1\nWIDTH 4\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 4\nDATA ascii\n"
      "0 0 0 4278190335\n1 0 0 65280\n0 1 0 255\nnan nan nan 0\n");
  {
    std::string bin = "VERSION 0.7\nFIELDS x y z normal_x normal_y normal_z\nSIZE 4 4 4 4 4 4\nTYPE F F F F F F\n"
                      "COUNT 1 1 1 1 1 1\nWIDTH 2\nHEIGHT 2\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 4\nDATA binary\n";
    const float pts[4][6] = {{0, 0, 0, 0, 0, 1}, {1, 0, 0, 0, 0, 1}, {0, 1, 0, 0, 0, 1}, {1, 1, 0, 0, 0, 1}};
    for (const auto& p : pts)
      for (float f : p) append(bin, f);
    put("read_pcd", "organized_binary.pcd", bin);
  }
  put("read_pcd", "old_style.pcd", "COLUMNS x y z\nSIZE 8 8 8\nTYPE F F F\nWIDTH 2\nPOINTS 2\nDATA ascii\n0 0 0\n1 2 3\n");
}

// Byte strings in the encoding the C ABI targets read (see fuzz_capi_*.cpp and Input).
void capi_seeds() {
  auto bytes = [](std::initializer_list<int> v) {
    std::string s;
    for (int x : v) s += char(uint8_t(x));
    return s;
  };
  // fuzz_capi_triangulate: mode, n, [sphere radius byte, edits] or numbers, option bytes.
  put("capi_triangulate", "sphere_defaults", bytes({2, 40, 0, 0, 0, 0}));
  put("capi_triangulate", "sphere_raw", bytes({2, 48, 0, 0, 16, 1, 0}));
  put("capi_triangulate", "sphere_normals_cancel", bytes({3, 60, 0, 0, 0, 8, 3}));
  put("capi_triangulate", "sphere_f32_attribute", bytes({6 | 8, 30, 8, 0, 4, 1, 1, 2, 3, 4, 5, 6, 0, 0}));
  {
    std::string s = bytes({0, 16});
    for (int i = 0; i < 16; ++i)  // a 4 x 4 square lattice: co-circular sets everywhere
      s += bytes({0, i % 4, 0, i / 4, 0, 0});
    s += bytes({0, 0});
    put("capi_triangulate", "square_lattice", s);
  }
  {
    std::string s = bytes({0, 6});
    for (int i = 0; i < 6; ++i) s += bytes({0, 1, 0, 1, 0, 1});  // all coincident
    s += bytes({0, 0});
    put("capi_triangulate", "coincident", s);
  }
  // fuzz_capi_mesh: mode, nv, nt, positions (mode-0 numbers), triangles, then smoothing.
  {
    const int v[6][3] = {{4, 0, 0}, {-4, 0, 0}, {0, 4, 0}, {0, -4, 0}, {0, 0, 4}, {0, 0, -4}};
    const int f[8][3] = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
    for (int smooth_mode : {0, 8, 8 | 4}) {
      std::string s = bytes({smooth_mode, 6, 8});
      for (const auto& p : v)
        for (int c : p) s += bytes({0, c});
      for (const auto& t : f)
        for (int c : t) s += bytes({c});
      if (smooth_mode & 4) s += bytes({3, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 1, 0, 0, 2});
      s += bytes({2, 3, 0});  // which: levels fuzzed, levels byte -> 1 level, size_mode 0
      put("capi_mesh", "octahedron_" + std::to_string(smooth_mode), s);
    }
    std::string fin = bytes({8, 5, 3, 0, 0, 0, 0, 0, 0, 0, 4, 0, 0, 0, 0, 0, 4, 0, 0, 0, 4, 0, 4, 0, 4, 0, 4, 0, 4,
                             0, 1, 2, 1, 3, 2, 1, 2, 4, 0, 0});
    put("capi_mesh", "fin_nonmanifold", fin);
  }
  // fuzz_capi_polygonize: mode, n - 1, positions (mode-0 numbers, x 0.25), [radii], options.
  {
    for (int mode : {0, 1, 2}) {
      std::string s = bytes({mode, 26});
      for (int i = 0; i < 27; ++i)  // a 3 x 3 x 3 lattice, spacing 0.5
        s += bytes({0, 2 * (i % 3), 0, 2 * ((i / 3) % 3), 0, 2 * (i / 9)});
      if (mode & 1)
        for (int i = 0; i < 27; ++i) s += bytes({1, 32 + i});  // radii 1.0 .. 1.4
      if (mode & 2)
        for (int i = 0; i < 27; ++i) s += bytes({1});  // strengths 1
      s += bytes({0, 0});
      put("capi_polygonize", "lattice_" + std::to_string(mode), s);
      // The same with anisotropic kernels (the byte after the options: anisotropic, fuzzed
      // min_neighbors 4) and, for mode 2, small pieces dropped and Taubin smoothing.
      s += bytes({mode == 2 ? 1 | 8 | 64 | 128 : 1 | 8, 6});
      if (mode == 2) s += bytes({0, 1, 4, 0, 0});  // min_component_particles 1, 3 Taubin iterations
      put("capi_polygonize", "lattice_anisotropic_" + std::to_string(mode), s);
    }
    std::string cancel = bytes({0, 7});
    for (int i = 0; i < 8; ++i) cancel += bytes({0, 4 * (i & 1), 0, 2 * ((i >> 1) & 1), 0, 4 * (i >> 2)});
    cancel += bytes({8 | 32, 0, 0, 0, 1, 8, 2});  // cell size fuzzed (0 -> default), budget, cancel at 2
    put("capi_polygonize", "box_budget_cancel", cancel);
  }
  // fuzz_capi_raycast: mode, n - 1, positions, field options byte, rays - 0, per ray
  // (flag, origin / number) and direction numbers, ray options, outputs mask, CSG op.
  {
    std::string s = bytes({0, 7});
    for (int i = 0; i < 8; ++i) s += bytes({0, 2 * (i & 1), 0, 2 * ((i >> 1) & 1), 0, 2 * (i >> 2)});
    s += bytes({0, 4});
    for (int r = 0; r < 4; ++r) {
      for (int a = 0; a < 3; ++a) s += bytes({1});              // origins: near a particle, 4 R away
      for (int a = 0; a < 3; ++a) s += bytes({0, a == r % 3 ? 4 : 1});  // directions
    }
    s += bytes({0, 0, 1});
    put("capi_raycast", "cube_4_rays", s);
    std::string k = s;
    k[0] = 3;
    put("capi_raycast", "cube_radii_strengths", k);
    // Anisotropic kernels: the field options byte's last bit, then their byte (min_neighbors 4).
    std::string a = s;
    const size_t at = 2 + 8 * 6;  // mode, n - 1, 8 positions of 3 two-byte numbers
    a[at] = char(128);
    a.insert(at + 1, bytes({1 | 8, 6}));
    put("capi_raycast", "cube_anisotropic", a);
  }
}

void shared_seeds(const fs::path& shared) {
  if (shared.empty() || !fs::is_directory(shared)) return;
  constexpr uintmax_t kMaxBytes = 2u << 20;  // the kinect frames are left out (5 MB); -max_len cuts the rest
  for (const auto& e : fs::recursive_directory_iterator(shared)) {
    if (!e.is_regular_file() || e.file_size() > kMaxBytes) continue;
    const std::string ext = e.path().extension().string();
    const std::string name = "shared_" + e.path().parent_path().filename().string() + "_" + e.path().filename().string();
    if (ext == ".ply") put("read_ply", name, slurp(e.path()));
    if (ext == ".obj") put("read_obj", name, slurp(e.path()));
    if (ext == ".pcd") put("read_pcd", name, slurp(e.path()));
    if (ext == ".bgeo") put("read_bgeo", name, slurp(e.path()));
    if (ext == ".vtk") put("read_vtk", name, std::string(1, '\0') + slurp(e.path()));
    if (ext == ".vtu") put("read_vtk", name, std::string(1, '\1') + slurp(e.path()));
    if (ext == ".vtp") put("read_vtk", name, std::string(1, '\2') + slurp(e.path()));
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: pm_fuzz_seeds OUT [SHARED_DATA]\n");
    return 2;
  }
  g_out = argv[1];
  fs::remove_all(g_out);
  fs::create_directories(g_out);
  file_seeds();
  capi_seeds();
  shared_seeds(argc > 2 ? fs::path(argv[2]) : fs::path());
  std::printf("fuzz seeds written to %s\n", g_out.c_str());
  return 0;
}
