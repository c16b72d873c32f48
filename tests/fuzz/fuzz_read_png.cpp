// Fuzz target: PNG files (read_png, the reader behind the render tests and tools):
// any bytes as a .png file. Checks: only particlemesh::Error escapes, and an image comes back
// with a pixel buffer of exactly width x height x 3 bytes.
#include "fuzz_support.h"
#include "particlemesh/core/error.h"
#include "particlemesh/io/png.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace particlemesh;
  static fuzz::TempFileCleanup cleanup{".png"};
  const std::string& path = fuzz::temp_file(".png", data, size);
  try {
    const Image img = read_png(path);
    PM_FUZZ_CHECK(img.width > 0 && img.height > 0);
    PM_FUZZ_CHECK(img.rgb.size() == size_t(img.width) * size_t(img.height) * 3);
  } catch (const Error& e) {
    PM_FUZZ_CHECK(e.status() != Status::Internal);
    PM_FUZZ_CHECK(e.what()[0] != '\0');
  }
  return 0;
}
