#include "surface.h"

#include <string>
#include <unordered_map>

#include <particlemesh/core/error.h>
#include <particlemesh/surface/triangulate.h>

namespace particlemesh_pcl::detail
{
  namespace
  {
    // Which particle each mesh vertex is. The surface stage keeps the particles as its
    // vertices (index i = particle i); should a stage ever reorder or drop vertices, they are
    // matched back by exact position, and a vertex that is no input point is an error
    // (MeshConstruction's output must index the input cloud).
    std::vector<std::uint32_t>
    vertexSource (const particlemesh::TriMesh &mesh, const particlemesh::PointCloud &particles)
    {
      std::vector<std::uint32_t> source (mesh.positions.size ());
      bool identity = mesh.positions.size () == particles.positions.size ();
      for (std::size_t v = 0; identity && v < source.size (); ++v)
        identity = mesh.positions[v] == particles.positions[v];
      if (identity)
      {
        for (std::size_t v = 0; v < source.size (); ++v)
          source[v] = static_cast<std::uint32_t> (v);
        return source;
      }
      struct Hash
      {
        std::size_t operator() (const particlemesh::Vec3 &p) const noexcept
        {
          const std::hash<double> h;
          return h (p.x) ^ (h (p.y) * 0x9e3779b97f4a7c15ull) ^ (h (p.z) * 0xc2b2ae3d27d4eb4full);
        }
      };
      std::unordered_map<particlemesh::Vec3, std::uint32_t, Hash> index;
      index.reserve (particles.size ());
      for (std::size_t i = particles.size (); i-- > 0;)  // the lowest index wins for duplicates
        index[particles.positions[i]] = static_cast<std::uint32_t> (i);
      for (std::size_t v = 0; v < source.size (); ++v)
      {
        const auto it = index.find (mesh.positions[v]);
        if (it == index.end ())
          throw particlemesh::Error (particlemesh::Status::Internal,
                                     "surface vertex " + std::to_string (v) + " is not an input point");
        source[v] = it->second;
      }
      return source;
    }
  }

  SurfaceMesh
  buildSurface (const particlemesh::PointCloud &particles, const particlemesh::SurfaceOptions &options, bool raw)
  {
    particlemesh::SurfaceResult result;
    if (raw)
    {
      particlemesh::TriangulateResult r = particlemesh::triangulate_raw (particles, options);
      result.mesh = std::move (r.mesh);
      result.triangulation = r.stats;
    }
    else
      result = particlemesh::reconstruct_surface (particles, options);

    SurfaceMesh out;
    out.vertex_source = vertexSource (result.mesh, particles);
    out.mesh = std::move (result.mesh);
    out.spacing = result.triangulation.spacing;
    out.spacing_estimated = result.triangulation.spacing_estimated;
    out.max_edge = result.triangulation.max_edge;
    out.surface = result.surface;
    return out;
  }
}
