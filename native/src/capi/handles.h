// Internal: what the opaque C handles hold.
#pragma once

#include "particlemesh/mesh/point_cloud.h"
#include "particlemesh/mesh/tri_mesh.h"

struct pm_cloud {
  particlemesh::PointCloud cloud;
};

struct pm_mesh {
  particlemesh::TriMesh mesh;
};
