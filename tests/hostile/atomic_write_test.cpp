// Every writer writes atomically: a write that fails half-way (here: the process's
// file size limit, as a full disk would) leaves neither a file under the requested name nor a
// temporary file, and an existing file under that name is left as it was.
//
// Before the hostile-input suite, OpenMesh's writers did not check their stream: a mesh cut at the size limit
// was renamed into place and reported as written.
#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <random>
#include <sys/resource.h>

#include "hostile_support.h"
#include "particlemesh/io/atomic_write.h"
#include "particlemesh/io/mesh_io.h"
#include "particlemesh/io/png.h"
#include "particlemesh/sample/shapes.h"
#include "support/test_support.h"

using namespace particlemesh;
using namespace particlemesh::test;
namespace fs = std::filesystem;

namespace test_detail {

/// RLIMIT_FSIZE lowered for the scope (SIGXFSZ ignored, so writes fail with EFBIG instead of
/// killing the process), restored after.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    getrlimit(RLIMIT_FSIZE, &saved_);
    old_handler_ = std::signal(SIGXFSZ, SIG_IGN);
    rlimit r = saved_;
    r.rlim_cur = bytes;
    setrlimit(RLIMIT_FSIZE, &r);
  }
  ~FileSizeLimit() {
    setrlimit(RLIMIT_FSIZE, &saved_);
    std::signal(SIGXFSZ, old_handler_);
  }

 private:
  rlimit saved_{};
  void (*old_handler_)(int) = nullptr;
};

}  // namespace test_detail

namespace {

std::vector<std::string> files_in(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

// `write(path)` must fail with IoError under a 10 kB limit, leaving `dir` as it was.
void expect_atomic_failure(const fs::path& dir, const std::string& name, const std::function<void(const std::string&)>& write) {
  const auto before = files_in(dir);
  {
    test_detail::FileSizeLimit limit(10000);
    PM_EXPECT_ERROR(write((dir / name).string()), Status::IoError, name);
  }
  EXPECT_EQ(files_in(dir), before) << name << ": a partial or temporary file was left";
  // With room, the same call writes the file.
  write((dir / name).string());
  EXPECT_TRUE(fs::exists(dir / name));
  EXPECT_GT(fs::file_size(dir / name), 10000u);
  // And a failing overwrite leaves the complete earlier file alone.
  const auto size = fs::file_size(dir / name);
  {
    test_detail::FileSizeLimit limit(10000);
    EXPECT_EQ(status_of([&] { write((dir / name).string()); }), Status::IoError);
  }
  EXPECT_EQ(fs::file_size(dir / name), size) << name;
  EXPECT_EQ(files_in(dir).size(), before.size() + 1);
}

}  // namespace

TEST(AtomicWrite, MeshWritersNeverLeaveATruncatedFile) {
  const auto dir = scratch_dir("mesh");
  const TriMesh m = icosphere_mesh(4);  // 2562 vertices with normals: about 60 kB
  TriMesh with_normals = m;
  with_normals.normals = m.positions;
  expect_atomic_failure(dir, "m.ply", [&](const std::string& p) { write_mesh(with_normals, p); });
  expect_atomic_failure(dir, "a.ply", [&](const std::string& p) { write_mesh(with_normals, p, {MeshFormat::PlyAscii, true, {}}); });
  expect_atomic_failure(dir, "m.obj", [&](const std::string& p) { write_mesh(with_normals, p); });
}

TEST(AtomicWrite, CloudAndTextWritersNeverLeaveATruncatedFile) {
  const auto dir = scratch_dir("cloud");
  const PointCloud c = fibonacci_sphere(2000);
  expect_atomic_failure(dir, "c.ply", [&](const std::string& p) { write_point_cloud(c, p); });
  expect_atomic_failure(dir, "c.xyz", [&](const std::string& p) { write_point_cloud(c, p); });
  const std::string text(50000, 'x');
  expect_atomic_failure(dir, "r.json", [&](const std::string& p) { write_file_atomically(p, text); });
}

TEST(AtomicWrite, PngWriterNeverLeavesATruncatedFile) {
  const auto dir = scratch_dir("png");
  Image img;
  img.width = 300;
  img.height = 200;
  std::mt19937 rng(7);
  for (int i = 0; i < img.width * img.height * 3; ++i) img.rgb.push_back(uint8_t(rng() >> 24));  // noise: no compression
  expect_atomic_failure(dir, "i.png", [&](const std::string& p) { write_png(img, p); });
}
