// Fuzz target: PLY files (OpenMesh's reader behind read_point_cloud / read_mesh, our header
// check in front of it), through the C++ API and the C ABI.
#include "fuzz_read_files.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  particlemesh::fuzz::read_both(data, size, ".ply", true, true);
  return 0;
}
