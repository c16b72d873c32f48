// The PCL bridge's files: PCD headers whose counts overflow, and the PLY writer
// (pcl::io::savePLYFileBinary behind particlemesh_pcl::savePLYFile) under a failing write.
#include <gtest/gtest.h>

#include <csignal>
#include <cstring>
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

// pcl::PCDReader reads lines after DATA as header lines while they start with a keyword:
// binary data beginning with the bytes "COLUMNS" became a second FIELDS line and PCL crashed
// reading the points (found by fuzzing; a segfault in the Release CLI before the check).
TEST(PclBridgeFiles, BinaryDataThatReadsLikeAHeaderLineIsRefused) {
  const auto dir = scratch_dir("pcdheaderdata");
  const std::string h = "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\n"
                        "HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA binary\n";
  const unsigned char body[] = {0x43, 0x4f, 0x4c, 0x55, 0x4d, 0x4e, 0x53, 0xa8, 0xe4, 0x5a, 0xbf, 0x8c,
                                0xd5, 0x4d, 0x62, 0x3f, 0x89, 0x8b, 0x8b, 0xff, 0xa3, 0x59, 0x9c, 0xbd};
  std::ofstream(dir / "columns.pcd", std::ios::binary) << h << std::string(reinterpret_cast<const char*>(body), sizeof body);
  PM_EXPECT_ERROR(particlemesh_pcl::loadParticles((dir / "columns.pcd").string()), Status::FormatError,
                  "the data after the DATA line begins like a header line ('COLUMNS...')");
  // After a line PCL skips (a '#' comment, an empty line) the next one counts too.
  std::ofstream(dir / "comment.pcd", std::ios::binary) << h << "#x\n\nWIDTH 9\n" << std::string(24, '\1');
  PM_EXPECT_ERROR(particlemesh_pcl::loadParticles((dir / "comment.pcd").string()), Status::FormatError, "('WIDTH...')");
  // A header line of only whitespace: pcl::PCDReader crashed on it before the first keyword.
  for (const char* blank : {" ", "\t", "\r"}) {
    std::ofstream(dir / "blank.pcd", std::ios::binary) << blank << "\n" << h << std::string(24, '\0');
    PM_EXPECT_ERROR(particlemesh_pcl::loadParticles((dir / "blank.pcd").string()), Status::FormatError,
                    "header line 1 holds only whitespace");
  }
  // A control byte in a header line: PCL splits "DATA\fbinary" as one word and threw out of
  // its reader (an abort, found by fuzzing).
  for (const std::string& sep : {std::string("\f"), std::string("\v"), std::string(1, '\0')}) {
    std::string bad = h;
    bad.replace(bad.find("DATA binary"), 11, "DATA" + sep + "binary");
    std::ofstream(dir / "control.pcd", std::ios::binary) << bad << std::string(24, '\0');
    PM_EXPECT_ERROR(particlemesh_pcl::loadParticles((dir / "control.pcd").string()), Status::FormatError,
                    "header line 11 holds the control byte 0x");
  }
  // Tabs and CRLF line ends are not control bytes to refuse.
  std::string tabs = h;
  tabs.replace(tabs.find("WIDTH 2"), 7, "WIDTH\t2\r");
  std::ofstream(dir / "tabs.pcd", std::ios::binary) << tabs << std::string(24, '\0');
  EXPECT_EQ(particlemesh_pcl::loadParticles((dir / "tabs.pcd").string()).size(), 2u);
  // Ordinary binary data (here: its first byte a newline) reads.
  float pts[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  std::memcpy(pts, "\n\0\0\0", 4);
  std::string ok = h;
  ok.replace(ok.find("WIDTH 2"), 7, "WIDTH 3").replace(ok.find("POINTS 2"), 8, "POINTS 3");
  std::ofstream(dir / "ok.pcd", std::ios::binary) << ok << std::string(reinterpret_cast<const char*>(pts), sizeof pts);
  EXPECT_EQ(particlemesh_pcl::loadParticles((dir / "ok.pcd").string()).size(), 3u);
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
