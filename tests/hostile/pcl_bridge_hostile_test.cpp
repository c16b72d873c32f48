// The PCL bridge's files (issue 9): PCD headers whose counts overflow, and the PLY writer
// (pcl::io::savePLYFileBinary behind particlemesh_pcl::savePLYFile) under a failing write.
#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <sys/resource.h>

#include "hostile_support.h"
#include "particlemesh/sample/shapes.h"
#include "particlemesh_pcl/conversions.h"
#include "particlemesh_pcl/io.h"
#include "support/test_support.h"

using namespace particlemesh;
using namespace particlemesh::test;
namespace fs = std::filesystem;

TEST(PclBridgeFiles, PcdCountsThatOverflowAreRefused) {
  const auto dir = scratch_dir("pcd");
  // 4294967295 x 4294967295 points x 2^20 x 12 bytes: the product wraps around 64 bits, which
  // made the truncation check pass.
  std::string h = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 4294967295\n"
                  "HEIGHT 4294967295\nPOINTS 18446744065119617025\nDATA binary\n";
  std::ofstream(dir / "o.pcd", std::ios::binary) << h << std::string(64, '\0');
  PM_EXPECT_ERROR(particlemesh_pcl::loadParticles((dir / "o.pcd").string()), Status::FormatError, "o.pcd");
  std::string c = "VERSION 0.7\nFIELDS x y z w\nSIZE 4 4 4 8\nTYPE F F F F\nCOUNT 1 1 1 1048576\nWIDTH 4294967295\n"
                  "HEIGHT 4294967295\nDATA binary\n";
  std::ofstream(dir / "c.pcd", std::ios::binary) << c << std::string(64, '\0');
  PM_EXPECT_ERROR(particlemesh_pcl::loadParticles((dir / "c.pcd").string()), Status::FormatError, "c.pcd");
}

TEST(PclBridgeFiles, PlyWriterNeverLeavesATruncatedFile) {
  const auto dir = scratch_dir("ply");
  TriMesh m = icosphere_mesh(4);
  m.normals = m.positions;
  pcl::PolygonMesh pm;
  particlemesh_pcl::toPolygonMesh(m, pm);
  const std::string path = (dir / "p.ply").string();
  {
    rlimit saved{};
    getrlimit(RLIMIT_FSIZE, &saved);
    auto old = std::signal(SIGXFSZ, SIG_IGN);
    rlimit r = saved;
    r.rlim_cur = 10000;
    setrlimit(RLIMIT_FSIZE, &r);
    const Status s = status_of([&] { particlemesh_pcl::savePLYFile(path, pm); });
    setrlimit(RLIMIT_FSIZE, &saved);
    std::signal(SIGXFSZ, old);
    EXPECT_EQ(s, Status::IoError);
  }
  EXPECT_TRUE(fs::is_empty(dir)) << "a partial or temporary file was left";
  particlemesh_pcl::savePLYFile(path, pm);
  EXPECT_GT(fs::file_size(path), 10000u);
}
