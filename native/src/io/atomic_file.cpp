#include "io/atomic_file.h"

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <system_error>
#include <unistd.h>

#include "particlemesh/core/error.h"

namespace particlemesh::detail {

namespace fs = std::filesystem;

AtomicFile::AtomicFile(const std::string& target) : target_(target) {
  static std::atomic<unsigned> counter{0};
  const fs::path p(target);
  if (p.filename().empty()) throw Error(Status::InvalidArgument, "output path '" + target + "' names no file");
  const fs::path dir = p.parent_path();
  if (!dir.empty() && !fs::is_directory(dir))
    throw Error(Status::IoError, "cannot write '" + target + "': folder '" + dir.string() + "' does not exist");
  const std::string name = "." + p.stem().string() + ".tmp" + std::to_string(::getpid()) + "_" +
                           std::to_string(counter++) + p.extension().string();
  temp_ = (dir / name).string();
}

AtomicFile::~AtomicFile() {
  if (!committed_) std::remove(temp_.c_str());
}

void AtomicFile::commit() {
  if (std::rename(temp_.c_str(), target_.c_str()) != 0) {
    const int e = errno;
    throw Error(Status::IoError, "cannot write '" + target_ + "': " + std::strerror(e));
  }
  committed_ = true;
}

}  // namespace particlemesh::detail

#include <fstream>

#include "particlemesh/io/atomic_write.h"

namespace particlemesh {

void write_file_atomically(const std::string& path, const std::string& contents) {
  detail::AtomicFile file(path);
  {
    std::ofstream out(file.temp_path(), std::ios::binary);
    if (!out) throw Error(Status::IoError, "cannot write '" + path + "': " + std::strerror(errno));
    out.write(contents.data(), std::streamsize(contents.size()));
    out.flush();
    if (!out) throw Error(Status::IoError, "cannot write '" + path + "': write failed");
  }
  file.commit();
}

}  // namespace particlemesh
