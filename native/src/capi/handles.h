// Internal: what the opaque C handles hold.
#pragma once

#include "particlemesh/mesh/point_cloud.h"
#include "particlemesh/mesh/tri_mesh.h"
#include "particlemesh/smooth/smoother.h"

struct pm_cloud {
  particlemesh::PointCloud cloud;
};

struct pm_mesh {
  particlemesh::TriMesh mesh;
};

struct pm_smoother {
  particlemesh::Smoother smoother;
};
