// Fuzz target: OBJ files (io/obj_reader.cpp behind read_mesh), through the C++ API and the
// C ABI. The first byte picks the extension among .obj, .off and .stl: the other mesh formats
// read_mesh accepts go through the same door.
#include "fuzz_read_files.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const char* ext = ".obj";
  if (size > 0 && data[0] == 0xFF) ext = ".off";  // seeds for OFF/STL start with this marker
  if (size > 0 && data[0] == 0xFE) ext = ".stl";
  if (size > 0 && (data[0] == 0xFF || data[0] == 0xFE)) {
    ++data;
    --size;
  }
  particlemesh::fuzz::read_both(data, size, ext, false, true);
  return 0;
}
