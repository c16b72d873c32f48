// Fuzz target: VTK particle files (our own readers, which keep the core free of VTK): the first
// byte picks the format - legacy .vtk, XML .vtu or .vtp - and the rest is the file, read as
// particles and as a mesh through the C++ API and the C ABI.
#include "fuzz_read_files.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  static const char* const kExtensions[3] = {".vtk", ".vtu", ".vtp"};
  particlemesh::fuzz::read_both(data + 1, size - 1, kExtensions[data[0] % 3], true, true);
  return 0;
}
