// Conversions between PCL's clouds/meshes and particlemesh's flat structs, plus the
// precompiled instantiations of the toParticles templates.
#include <pcl/impl/instantiate.hpp>
#include <pcl/point_types.h>

#include <particlemesh_pcl/conversions.h>
#include <particlemesh_pcl/impl/conversions.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <optional>
#include <string>

#include <particlemesh/core/error.h>

namespace particlemesh_pcl
{
  namespace
  {
    using particlemesh::Error;
    using particlemesh::Status;

    // Reads one scalar field of a PCLPointCloud2, whatever its numeric type. Hand-written
    // (not pcl::fromPCLPointCloud2) because it must accept any type and layout a PCD file
    // may declare (double x, int intensity, rgb as U or F) without picking a point type.
    class FieldReader
    {
      public:
        FieldReader (const pcl::PCLPointCloud2 &cloud, const pcl::PCLPointField &field)
          : data_ (cloud.data.data ()), offset_ (field.offset), type_ (field.datatype),
            width_ (cloud.width), point_step_ (cloud.point_step), row_step_ (cloud.row_step) {}

        double
        value (std::size_t i) const
        {
          const std::uint8_t *p = at (i);
          switch (type_)
          {
            case pcl::PCLPointField::INT8: return load<std::int8_t> (p);
            case pcl::PCLPointField::UINT8: return load<std::uint8_t> (p);
            case pcl::PCLPointField::INT16: return load<std::int16_t> (p);
            case pcl::PCLPointField::UINT16: return load<std::uint16_t> (p);
            case pcl::PCLPointField::INT32: return load<std::int32_t> (p);
            case pcl::PCLPointField::UINT32: return load<std::uint32_t> (p);
            case pcl::PCLPointField::INT64: return static_cast<double> (load<std::int64_t> (p));
            case pcl::PCLPointField::UINT64: return static_cast<double> (load<std::uint64_t> (p));
            case pcl::PCLPointField::FLOAT32: return load<float> (p);
            case pcl::PCLPointField::FLOAT64: return load<double> (p);
            default: return std::numeric_limits<double>::quiet_NaN ();
          }
        }

        /// The 32 bits of a packed colour (PCL stores rgb as a float or a uint32 holding
        /// 0x00RRGGBB / 0xAARRGGBB).
        std::uint32_t
        bits32 (std::size_t i) const
        {
          return load<std::uint32_t> (at (i));
        }

        static std::size_t
        sizeOf (std::uint8_t type)
        {
          switch (type)
          {
            case pcl::PCLPointField::INT8: case pcl::PCLPointField::UINT8: return 1;
            case pcl::PCLPointField::INT16: case pcl::PCLPointField::UINT16: return 2;
            case pcl::PCLPointField::INT32: case pcl::PCLPointField::UINT32:
            case pcl::PCLPointField::FLOAT32: return 4;
            case pcl::PCLPointField::INT64: case pcl::PCLPointField::UINT64:
            case pcl::PCLPointField::FLOAT64: return 8;
            default: return 0;
          }
        }

      private:
        template <typename T> static T
        load (const std::uint8_t *p)
        {
          T v;
          std::memcpy (&v, p, sizeof (T));
          return v;
        }

        const std::uint8_t *
        at (std::size_t i) const
        {
          return data_ + (i / width_) * row_step_ + (i % width_) * point_step_ + offset_;
        }

        const std::uint8_t *data_;
        std::size_t offset_;
        std::uint8_t type_;
        std::size_t width_, point_step_, row_step_;
    };

    const pcl::PCLPointField *
    findField (const pcl::PCLPointCloud2 &cloud, const char *name)
    {
      for (const auto &f : cloud.fields)
        if (f.name == name)
          return &f;
      return nullptr;
    }

    // Check the blob's layout so that FieldReader never reads outside it.
    void
    checkLayout (const pcl::PCLPointCloud2 &cloud)
    {
      const std::size_t n = std::size_t (cloud.width) * cloud.height;
      if (n == 0)
        return;
      if (std::size_t (cloud.point_step) * cloud.width > cloud.row_step)
        throw Error (Status::FormatError, "cloud row_step " + std::to_string (cloud.row_step) +
                                          " is smaller than width x point_step");
      if (cloud.data.size () < std::size_t (cloud.row_step) * cloud.height)
        throw Error (Status::FormatError, "cloud data holds " + std::to_string (cloud.data.size ()) +
                                          " bytes, width x height needs " +
                                          std::to_string (std::size_t (cloud.row_step) * cloud.height));
      for (const auto &f : cloud.fields)
      {
        const std::size_t size = FieldReader::sizeOf (f.datatype);
        if (size == 0)
          throw Error (Status::FormatError, "field '" + f.name + "' has unknown datatype " +
                                            std::to_string (int (f.datatype)));
        if (f.offset + size * std::max<std::size_t> (f.count, 1) > cloud.point_step)
          throw Error (Status::FormatError, "field '" + f.name + "' lies outside point_step " +
                                            std::to_string (cloud.point_step));
      }
    }

    /// A field carried as a channel of its name: one reader per value (a field's COUNT).
    struct ExtraField
    {
      std::string name;
      std::vector<FieldReader> values;
    };

    struct Channels
    {
      std::optional<FieldReader> x, y, z, nx, ny, nz, rgb, intensity;
      std::vector<ExtraField> extra;  ///< every other field, in the cloud's order
    };

    Channels
    channels (const pcl::PCLPointCloud2 &cloud)
    {
      checkLayout (cloud);
      Channels c;
      const char *names[3] = {"x", "y", "z"};
      std::optional<FieldReader> *xyz[3] = {&c.x, &c.y, &c.z};
      for (int k = 0; k < 3; ++k)
      {
        const pcl::PCLPointField *f = findField (cloud, names[k]);
        if (!f)
        {
          std::string have;
          for (const auto &g : cloud.fields)
            have += (have.empty () ? "" : " ") + g.name;
          throw Error (Status::FormatError, std::string ("missing field '") + names[k] +
                                            "' (fields: " + (have.empty () ? "none" : have) + ")");
        }
        xyz[k]->emplace (cloud, *f);
      }
      const pcl::PCLPointField *nx = findField (cloud, "normal_x");
      const pcl::PCLPointField *ny = findField (cloud, "normal_y");
      const pcl::PCLPointField *nz = findField (cloud, "normal_z");
      if (nx && ny && nz)
      {
        c.nx.emplace (cloud, *nx);
        c.ny.emplace (cloud, *ny);
        c.nz.emplace (cloud, *nz);
      }
      const pcl::PCLPointField *rgb = findField (cloud, "rgb");
      if (!rgb)
        rgb = findField (cloud, "rgba");
      if (rgb && FieldReader::sizeOf (rgb->datatype) == 4)
        c.rgb.emplace (cloud, *rgb);
      const pcl::PCLPointField *in = findField (cloud, "intensity");
      if (in)
        c.intensity.emplace (cloud, *in);
      // Every other field (a segmentation's label, PCL's curvature, a descriptor) travels as a
      // channel of its name, as a PLY file's other vertex properties do; "_" is PCL's padding.
      for (const auto &f : cloud.fields)
      {
        const bool used = f.name == "x" || f.name == "y" || f.name == "z" || &f == in ||
                          (&f == rgb && c.rgb) || (c.nx && (f.name == "normal_x" || f.name == "normal_y" || f.name == "normal_z"));
        if (used || f.name.empty () || f.name[0] == '_')
          continue;
        ExtraField e{f.name, {}};
        if (e.name == kColorAttribute || e.name == kIntensityAttribute)
          e.name += "_field";  // the names of the colour and intensity channels are taken
        const std::size_t size = FieldReader::sizeOf (f.datatype);
        for (std::uint32_t k = 0; k < std::max<std::uint32_t> (f.count, 1); ++k)
        {
          pcl::PCLPointField one = f;
          one.offset = static_cast<std::uint32_t> (f.offset + k * size);
          e.values.emplace_back (cloud, one);
        }
        c.extra.push_back (std::move (e));
      }
      // Fields name_0, name_1, ... in a row (how particlemesh's PLY writer stores a vector
      // channel) are one channel "name" again.
      std::vector<ExtraField> joined;
      for (std::size_t i = 0; i < c.extra.size ();)
      {
        const std::string &first = c.extra[i].name;
        std::size_t k = 0;
        const bool vector_start = first.size () > 2 && first.compare (first.size () - 2, 2, "_0") == 0 &&
                                  c.extra[i].values.size () == 1;
        const std::string base = vector_start ? first.substr (0, first.size () - 2) : std::string ();
        while (vector_start && i + k < c.extra.size () && c.extra[i + k].values.size () == 1 &&
               c.extra[i + k].name == base + "_" + std::to_string (k))
          ++k;
        if (k < 2)
        {
          joined.push_back (std::move (c.extra[i++]));
          continue;
        }
        ExtraField v{base, {}};
        for (std::size_t j = 0; j < k; ++j)
          v.values.push_back (c.extra[i + j].values[0]);
        joined.push_back (std::move (v));
        i += k;
      }
      c.extra = std::move (joined);
      return c;
    }

    void
    appendColor (std::vector<float> &values, std::uint32_t packed)
    {
      values.push_back (float ((packed >> 16) & 0xff) / 255.f);
      values.push_back (float ((packed >> 8) & 0xff) / 255.f);
      values.push_back (float (packed & 0xff) / 255.f);
    }

    const particlemesh::VertexAttribute *
    findAttribute (const particlemesh::TriMesh &mesh, const char *name, int components)
    {
      for (const auto &a : mesh.attributes)
        if (a.name == name && a.components == components &&
            a.values.size () == mesh.positions.size () * std::size_t (components))
          return &a;
      return nullptr;
    }
  }

  ConversionReport
  toParticles (const pcl::PCLPointCloud2 &cloud, particlemesh::PointCloud &particles,
               pcl::Indices &index_map)
  {
    const Channels c = channels (cloud);
    const std::size_t n = std::size_t (cloud.width) * cloud.height;
    ConversionReport report;
    report.input_points = n;
    report.width = cloud.width;
    report.height = cloud.height;
    report.organized = cloud.height > 1;

    particlemesh::PointCloud out;
    pcl::Indices map;
    particlemesh::VertexAttribute color{kColorAttribute, 3, {}};
    particlemesh::VertexAttribute intensity{kIntensityAttribute, 1, {}};
    std::vector<particlemesh::VertexAttribute> extra;
    for (const ExtraField &e : c.extra)
      extra.push_back ({e.name, int (e.values.size ()), {}});
    out.positions.reserve (n);
    map.reserve (n);
    for (std::size_t i = 0; i < n; ++i)
    {
      const particlemesh::Vec3 p{c.x->value (i), c.y->value (i), c.z->value (i)};
      if (!particlemesh::is_finite (p))
      {
        ++report.invalid_points;
        continue;
      }
      map.push_back (static_cast<pcl::index_t> (i));
      out.positions.push_back (p);
      if (c.nx)
      {
        const particlemesh::Vec3 nrm{c.nx->value (i), c.ny->value (i), c.nz->value (i)};
        if (!particlemesh::is_finite (nrm) || particlemesh::squared_norm (nrm) == 0)
          ++report.invalid_normals;
        out.normals.push_back (nrm);
      }
      if (c.rgb)
        appendColor (color.values, c.rgb->bits32 (i));
      if (c.intensity)
        intensity.values.push_back (float (c.intensity->value (i)));
      for (std::size_t e = 0; e < extra.size (); ++e)
        for (const FieldReader &r : c.extra[e].values)
          extra[e].values.push_back (float (r.value (i)));
    }
    if (report.invalid_normals > 0)
      out.normals.clear ();
    if (c.rgb)
      out.attributes.push_back (std::move (color));
    if (c.intensity)
      out.attributes.push_back (std::move (intensity));
    for (auto &a : extra)
      out.attributes.push_back (std::move (a));
    report.valid_points = out.positions.size ();
    report.has_normals = !out.normals.empty ();
    report.has_color = c.rgb.has_value ();
    report.has_intensity = c.intensity.has_value ();
    particles = std::move (out);
    index_map = std::move (map);
    return report;
  }

  void
  toPolygons (const particlemesh::TriMesh &mesh, const pcl::Indices &index_map,
              std::vector<pcl::Vertices> &polygons)
  {
    if (!index_map.empty () && index_map.size () != mesh.positions.size ())
      throw Error (Status::InvalidArgument, "index_map has " + std::to_string (index_map.size ()) +
                                            " entries, the mesh " + std::to_string (mesh.positions.size ()) +
                                            " vertices");
    std::vector<pcl::Vertices> out (mesh.triangles.size ());
    for (std::size_t t = 0; t < mesh.triangles.size (); ++t)
    {
      out[t].vertices.resize (3);
      for (int c = 0; c < 3; ++c)
      {
        const std::uint32_t v = mesh.triangles[t][c];
        if (v >= mesh.positions.size ())
          throw Error (Status::InvalidArgument, "triangles[" + std::to_string (t) + "] uses vertex " +
                                                std::to_string (v) + " of " + std::to_string (mesh.positions.size ()));
        out[t].vertices[c] = index_map.empty () ? static_cast<pcl::index_t> (v) : index_map[v];
      }
    }
    polygons = std::move (out);
  }

  void
  toPolygonMesh (const particlemesh::TriMesh &mesh, pcl::PolygonMesh &output)
  {
    const bool normals = mesh.normals.size () == mesh.positions.size () && !mesh.normals.empty ();
    const particlemesh::VertexAttribute *color = findAttribute (mesh, kColorAttribute, 3);
    const particlemesh::VertexAttribute *intensity = findAttribute (mesh, kIntensityAttribute, 1);

    pcl::PCLPointCloud2 cloud;
    auto add = [&cloud] (const char *name) {
      pcl::PCLPointField f;
      f.name = name;
      f.offset = static_cast<pcl::uindex_t> (cloud.fields.size () * 4);
      f.datatype = pcl::PCLPointField::FLOAT32;
      f.count = 1;
      cloud.fields.push_back (f);
    };
    add ("x"); add ("y"); add ("z");
    if (normals) { add ("normal_x"); add ("normal_y"); add ("normal_z"); }
    if (color) add ("rgb");  // PCL's convention: packed 0x00RRGGBB in a float32 field
    if (intensity) add ("intensity");

    const std::size_t n = mesh.positions.size ();
    cloud.height = 1;
    cloud.width = static_cast<pcl::uindex_t> (n);
    cloud.is_bigendian = false;
    cloud.point_step = static_cast<pcl::uindex_t> (cloud.fields.size () * 4);
    cloud.row_step = static_cast<pcl::uindex_t> (cloud.point_step * n);
    cloud.is_dense = true;
    cloud.data.resize (std::size_t (cloud.point_step) * n);
    for (std::size_t i = 0; i < n; ++i)
    {
      float v[8];
      int k = 0;
      v[k++] = float (mesh.positions[i].x);
      v[k++] = float (mesh.positions[i].y);
      v[k++] = float (mesh.positions[i].z);
      if (!std::isfinite (v[0]) || !std::isfinite (v[1]) || !std::isfinite (v[2]))
        cloud.is_dense = false;
      if (normals)
      {
        v[k++] = float (mesh.normals[i].x);
        v[k++] = float (mesh.normals[i].y);
        v[k++] = float (mesh.normals[i].z);
      }
      if (color)
      {
        std::uint32_t packed = 0;
        for (int ch = 0; ch < 3; ++ch)
        {
          const float f = std::clamp (color->values[3 * i + ch], 0.f, 1.f);
          packed = (packed << 8) | std::uint32_t (std::lround (f * 255.f));
        }
        v[k++] = std::bit_cast<float> (packed);
      }
      if (intensity)
        v[k++] = intensity->values[i];
      std::memcpy (cloud.data.data () + i * cloud.point_step, v, std::size_t (k) * 4);
    }

    std::vector<pcl::Vertices> polygons;
    toPolygons (mesh, {}, polygons);
    output.header = pcl::PCLHeader ();
    output.cloud = std::move (cloud);
    output.polygons = std::move (polygons);
  }

  void
  fromPolygonMesh (const pcl::PolygonMesh &input, particlemesh::TriMesh &mesh)
  {
    const pcl::PCLPointCloud2 &cloud = input.cloud;
    const Channels c = channels (cloud);
    const std::size_t n = std::size_t (cloud.width) * cloud.height;

    particlemesh::TriMesh out;
    out.positions.resize (n);
    bool normals_ok = c.nx.has_value ();
    if (normals_ok)
      out.normals.resize (n);
    particlemesh::VertexAttribute color{kColorAttribute, 3, {}};
    for (std::size_t i = 0; i < n; ++i)
    {
      out.positions[i] = {c.x->value (i), c.y->value (i), c.z->value (i)};
      if (normals_ok)
        out.normals[i] = {c.nx->value (i), c.ny->value (i), c.nz->value (i)};
      if (c.rgb)
        appendColor (color.values, c.rgb->bits32 (i));
    }
    if (c.rgb)
      out.attributes.push_back (std::move (color));
    if (c.intensity)
    {
      particlemesh::VertexAttribute in{kIntensityAttribute, 1, {}};
      for (std::size_t i = 0; i < n; ++i)
        in.values.push_back (float (c.intensity->value (i)));
      out.attributes.push_back (std::move (in));
    }
    for (const ExtraField &e : c.extra)
    {
      particlemesh::VertexAttribute a{e.name, int (e.values.size ()), {}};
      a.values.reserve (n * e.values.size ());
      for (std::size_t i = 0; i < n; ++i)
        for (const FieldReader &r : e.values)
          a.values.push_back (float (r.value (i)));
      out.attributes.push_back (std::move (a));
    }

    for (std::size_t p = 0; p < input.polygons.size (); ++p)
    {
      const auto &v = input.polygons[p].vertices;
      for (std::size_t k = 0; k < v.size (); ++k)
        if (v[k] < 0 || static_cast<std::size_t> (v[k]) >= n)
          throw Error (Status::FormatError, "polygons[" + std::to_string (p) + "] uses point " +
                                            std::to_string (v[k]) + " of a cloud of " + std::to_string (n));
      for (std::size_t k = 1; k + 1 < v.size (); ++k)  // fan
        out.triangles.push_back ({std::uint32_t (v[0]), std::uint32_t (v[k]), std::uint32_t (v[k + 1])});
    }
    mesh = std::move (out);
  }
}

// Precompiled for the point types the issue names (PCL's PCL_INSTANTIATE idiom).
#define PM_PCL_POINT_TYPES \
  (pcl::PointXYZ)(pcl::PointNormal)(pcl::PointXYZRGB)(pcl::PointXYZRGBNormal)(pcl::PointXYZI)
PCL_INSTANTIATE (toParticles, PM_PCL_POINT_TYPES)
