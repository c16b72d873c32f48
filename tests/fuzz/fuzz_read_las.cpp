// Fuzz target: ASPRS LAS lidar files (our own reader), through the C++ API and the C ABI.
#include "fuzz_read_files.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  particlemesh::fuzz::read_both(data, size, ".las", true, false);
  return 0;
}
