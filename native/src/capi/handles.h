// Internal: what the opaque C handles hold.
#pragma once

#include <vector>

#include "particlemesh/io/frame_collection.h"
#include "particlemesh/mesh/point_cloud.h"
#include "particlemesh/mesh/tri_mesh.h"
#include "particlemesh/smooth/smoother.h"

struct pm_cloud {
  particlemesh::PointCloud cloud;
};

struct pm_mesh {
  particlemesh::TriMesh mesh;
};

struct pm_frame_collection {
  std::vector<particlemesh::CollectionFrame> frames;
};

struct pm_smoother {
  particlemesh::Smoother smoother;
};
