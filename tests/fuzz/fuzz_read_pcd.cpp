// Fuzz target: PCD files through the PCL bridge's checked reader (the file read once; our
// header check and ASCII parser, pcl::PCDReader's header and binary decoding on the same
// bytes; then the conversion to particles).
#include <pcl/console/print.h>

#include "fuzz_read_files.h"
#include "particlemesh_pcl/io.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);  // PCL's own messages: noise here
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace particlemesh;
  static fuzz::TempFileCleanup cleanup{".pcd"};
  const std::string& path = fuzz::temp_file(".pcd", data, size);
  try {
    particlemesh_pcl::LoadReport report;
    pcl::Indices map;
    const PointCloud c = particlemesh_pcl::loadParticles(path, &report, &map);
    fuzz::check_cloud(c);
    PM_FUZZ_CHECK(map.size() == c.size());
    PM_FUZZ_CHECK(report.conversion.valid_points == c.size());
    for (size_t i = 0; i < map.size(); ++i) {
      PM_FUZZ_CHECK(map[i] >= 0 && size_t(map[i]) < report.conversion.input_points);
      if (i > 0) PM_FUZZ_CHECK(map[i] > map[i - 1]);
    }
    for (const auto& a : c.attributes) PM_FUZZ_CHECK(a.values.size() == c.size() * size_t(a.components));
  } catch (const Error& e) {
    PM_FUZZ_CHECK(e.status() != Status::Internal);
    PM_FUZZ_CHECK(e.what()[0] != '\0');
  }
  return 0;
}
