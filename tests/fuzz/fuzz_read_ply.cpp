// Fuzz target: PLY files (io/ply_reader.cpp behind read_point_cloud / read_mesh), through the
// C++ API and the C ABI; what reads back is written and read again (fuzz_read_files.h).
#include "fuzz_read_files.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  particlemesh::fuzz::read_both(data, size, ".ply", true, true);
  return 0;
}
