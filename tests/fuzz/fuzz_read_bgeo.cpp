// Fuzz target: Houdini classic .bgeo particle files (our own reader: no packaged library reads
// bgeo), plain or gzip-compressed, through the C++ API and the C ABI.
#include "fuzz_read_files.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  particlemesh::fuzz::read_both(data, size, ".bgeo", true, false);
  return 0;
}
