// Fuzz target: VTK particle files (our own readers, which keep the core free of VTK): the first
// byte picks the format - legacy .vtk, XML .vtu or .vtp, or (from 250 on) a ParaView
// collection, .pvd or .series - and the rest is the file, read as particles and as a mesh
// through the C++ API and the C ABI, or as a collection: its frames must come back by
// ascending finite time, inside its folder.
#include <filesystem>
#include <string>

#include "fuzz_read_files.h"
#include "particlemesh/io/frame_collection.h"

namespace {

void read_collection(const uint8_t* data, size_t size, const char* extension) {
  using namespace particlemesh;
  static fuzz::TempFileCleanup cleanup{extension};
  const std::string path = fuzz::temp_file(extension, data, size);
  const std::string folder = std::filesystem::path(path).parent_path().string() + "/";
  try {
    const std::vector<CollectionFrame> frames = read_frame_collection(path);
    PM_FUZZ_CHECK(!frames.empty());
    for (size_t i = 0; i < frames.size(); ++i) {
      PM_FUZZ_CHECK(std::isfinite(frames[i].time));
      PM_FUZZ_CHECK(i == 0 || frames[i - 1].time < frames[i].time);
      PM_FUZZ_CHECK(frames[i].path.compare(0, folder.size(), folder) == 0);
      for (const auto& part : std::filesystem::path(frames[i].path.substr(folder.size()))) PM_FUZZ_CHECK(part != "..");
    }
  } catch (const Error& e) {
    PM_FUZZ_CHECK(e.status() == Status::FormatError || e.status() == Status::IoError);
    PM_FUZZ_CHECK(e.what()[0] != '\0');
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  if (data[0] >= 250) {
    read_collection(data + 1, size - 1, data[0] % 2 ? ".series" : ".pvd");
    return 0;
  }
  static const char* const kExtensions[3] = {".vtk", ".vtu", ".vtp"};
  particlemesh::fuzz::read_both(data + 1, size - 1, kExtensions[data[0] % 3], true, true);
  return 0;
}
