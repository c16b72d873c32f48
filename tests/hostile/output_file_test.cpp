// Writing safely (OutputFile, and every writer through it): a link planted where a
// temporary might go is never followed; devices, FIFOs, links and hard links at the output
// path are written through, never replaced; a replaced file keeps its mode; a legal long name
// works; the temporaries of unfinished outputs can be removed from a signal handler; and the
// checks a program runs before any work name what is wrong.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "hostile_support.h"
#include "particlemesh/io/atomic_write.h"
#include "particlemesh/io/mesh_io.h"
#include "particlemesh/io/output_file.h"
#include "particlemesh/sample/shapes.h"
#include "support/test_support.h"

using namespace particlemesh;
using namespace particlemesh::test;
namespace fs = std::filesystem;

namespace {

std::string read_all(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

void put(const fs::path& p, const std::string& s) { std::ofstream(p, std::ios::binary) << s; }

std::vector<std::string> names_in(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

// The temporary's name was predictable (".<stem>.tmp<pid>_<n><ext>") and it was opened
// following links: a link planted there made the program overwrite the link's target (as
// root: any file). Now it is random and created exclusively (O_EXCL | O_NOFOLLOW).
TEST(OutputFiles, PlantedLinksAreNeverFollowed) {
  const auto dir = scratch_dir("plant");
  const fs::path victim = dir / "victim.txt";
  put(victim, "precious");
  // Every name the old scheme could pick for the next few hundred writes of this process.
  for (int n = 0; n < 400; ++n)
    fs::create_symlink(victim, dir / (".out.tmp" + std::to_string(::getpid()) + "_" + std::to_string(n) + ".ply"));
  const TriMesh m = icosphere_mesh(2);
  for (int k = 0; k < 3; ++k) write_mesh(m, (dir / "out.ply").string());
  EXPECT_EQ(read_all(victim), "precious");
  EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(dir / "out.ply")));
  EXPECT_EQ(read_mesh((dir / "out.ply").string()).triangles, m.triangles);
  // The temporary: one new entry while writing, a regular file, not a link, with a random
  // name unrelated to the process id; two outputs of one target get two names.
  {
    OutputFile a((dir / "t.ply").string()), b((dir / "t.ply").string());
    std::vector<std::string> temps;
    for (const std::string& n : names_in(dir))
      if (n.rfind(".pm", 0) == 0) temps.push_back(n);
    ASSERT_EQ(temps.size(), 2u);
    EXPECT_NE(temps[0], temps[1]);
    for (const std::string& t : temps) {
      EXPECT_EQ(t.find(std::to_string(::getpid())), std::string::npos) << t;
      EXPECT_LE(t.size(), 20u) << t;
      EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(dir / t))) << t;
    }
  }
  for (const std::string& n : names_in(dir)) EXPECT_NE(n.rfind(".pm", 0), 0u) << "temporary left: " << n;
}

// Devices, FIFOs, links and hard links are written through; before, each was replaced by a
// regular file (as root, `render -o /dev/null` replaced the machine's /dev/null).
TEST(OutputFiles, DevicesFifosAndLinksAreWrittenThrough) {
  const auto dir = scratch_dir("through");
  const TriMesh m = icosphere_mesh(2);
  write_mesh(m, (dir / "reference.ply").string());
  const std::string reference = read_all(dir / "reference.ply");

  // A FIFO: a reader gets the whole file; the FIFO stays a FIFO.
  const fs::path fifo = dir / "pipe.ply";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::string got;
  std::thread reader([&] { got = read_all(fifo); });
  write_mesh(m, fifo.string());
  reader.join();
  EXPECT_EQ(got, reference);
  EXPECT_TRUE(fs::is_fifo(fs::symlink_status(fifo)));

  // A character device (a null device made here, as the tests run as root in CI; elsewhere
  // the FIFO above covers the same path through the code).
  if (::geteuid() == 0) {
    const fs::path null = dir / "null";
    ASSERT_EQ(::mknod(null.c_str(), S_IFCHR | 0666, makedev(1, 3)), 0);
    write_mesh(m, null.string());
    write_file_atomically(null.string(), "report");
    EXPECT_TRUE(fs::is_character_file(fs::symlink_status(null)));
  } else {
    std::printf("not root: the device case (mknod) is not run here; the FIFO case covers the same code\n");
  }

  // A symbolic link: kept, its target written (in the target's folder).
  fs::create_directories(dir / "elsewhere");
  put(dir / "elsewhere" / "real.ply", "old");
  fs::create_symlink(dir / "elsewhere" / "real.ply", dir / "link.ply");
  write_mesh(m, (dir / "link.ply").string());
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dir / "link.ply")));
  EXPECT_EQ(read_all(dir / "elsewhere" / "real.ply"), reference);
  // A dangling link creates its target.
  fs::create_symlink(dir / "elsewhere" / "new.ply", dir / "dangling.ply");
  write_mesh(m, (dir / "dangling.ply").string());
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(dir / "dangling.ply")));
  EXPECT_EQ(read_all(dir / "elsewhere" / "new.ply"), reference);

  // A hard link: both names see the new contents.
  put(dir / "a.ply", "old");
  fs::create_hard_link(dir / "a.ply", dir / "b.ply");
  write_mesh(m, (dir / "a.ply").string());
  EXPECT_EQ(read_all(dir / "b.ply"), reference);
  EXPECT_EQ(fs::hard_link_count(dir / "a.ply"), 2u);

  // /dev/fd/N: the descriptor itself (here a pipe's write end).
  int p[2];
  ASSERT_EQ(::pipe(p), 0);
  std::string piped;
  std::thread drain([&] {
    char buf[4096];
    ssize_t n;
    while ((n = ::read(p[0], buf, sizeof buf)) > 0) piped.append(buf, size_t(n));
  });
  write_file_atomically("/dev/fd/" + std::to_string(p[1]), "through the descriptor\n");
  ::close(p[1]);
  drain.join();
  ::close(p[0]);
  EXPECT_EQ(piped, "through the descriptor\n");
  for (const std::string& n : names_in(dir)) EXPECT_NE(n.rfind(".pm", 0), 0u) << "temporary left: " << n;
}

// A replaced file keeps its permissions (before: 0644 whatever it was); a new file gets the
// umask's. A legal 250-byte name works (before: "File name too long", from the temporary's
// suffix).
TEST(OutputFiles, ReplacedFilesKeepTheirModeAndLongNamesWork) {
  const auto dir = scratch_dir("mode");
  const TriMesh m = icosphere_mesh(1);
  put(dir / "secret.ply", "old");
  fs::permissions(dir / "secret.ply", fs::perms::owner_read | fs::perms::owner_write);
  write_mesh(m, (dir / "secret.ply").string());
  EXPECT_EQ(fs::status(dir / "secret.ply").permissions() & fs::perms::mask, fs::perms::owner_read | fs::perms::owner_write);
  put(dir / "shared.json", "old");
  fs::permissions(dir / "shared.json", fs::perms(0664));
  write_file_atomically((dir / "shared.json").string(), "new");
  EXPECT_EQ(fs::status(dir / "shared.json").permissions() & fs::perms::mask, fs::perms(0664));
  const mode_t mask = ::umask(022);
  ::umask(mask);
  write_file_atomically((dir / "fresh.json").string(), "x");
  EXPECT_EQ(fs::status(dir / "fresh.json").permissions() & fs::perms::mask, fs::perms(0666 & ~mask));

  const std::string name = std::string(246, 'n') + ".ply";  // 250 bytes: legal (NAME_MAX is 255)
  write_mesh(m, (dir / name).string());
  EXPECT_EQ(read_mesh((dir / name).string()).triangles, m.triangles);
}

// The temporaries of unfinished outputs are registered for a signal handler
// (remove_unfinished_outputs, async-signal-safe), which the CLI calls on SIGTERM, SIGHUP,
// SIGQUIT, SIGPIPE and SIGINT while writing.
TEST(OutputFiles, UnfinishedTemporariesCanBeRemovedFromASignalHandler) {
  const auto dir = scratch_dir("signal");
  OutputFile done((dir / "done.json").string());
  done.write("complete");
  done.commit();
  OutputFile out((dir / "out.ply").string());
  out.write(std::string(100000, 'x'));
  ASSERT_EQ(names_in(dir).size(), 2u);  // done.json and the temporary
  remove_unfinished_outputs();
  EXPECT_EQ(names_in(dir), std::vector<std::string>{"done.json"});
  EXPECT_EQ(read_all(dir / "done.json"), "complete");
}

// What a program checks before any work (the CLI: a usage error, exit 2), each named.
TEST(OutputFiles, PathsAreCheckedBeforeAnyWork) {
  const auto dir = scratch_dir("check");
  std::string msg;
  auto refused = [&](const fs::path& p, const std::string& text) {
    SCOPED_TRACE(p.string());
    PM_EXPECT_ERROR(check_output_path(p.string()), Status::InvalidArgument, text);
  };
  refused(dir / "missing" / "o.ply", "the folder '" + (dir / "missing").string() + "' does not exist");
  fs::create_directories(dir / "folder");
  refused(dir / "folder", "is a folder");
  put(dir / "ro.ply", "x");
  fs::permissions(dir / "ro.ply", fs::perms::owner_read | fs::perms::group_read);
  refused(dir / "ro.ply", "the file is read-only");
  fs::create_directories(dir / "locked");
  fs::permissions(dir / "locked", fs::perms(0555));
  refused(dir / "locked" / "o.ply", "is read-only");
  refused(dir / "locked" / (std::string(256, 'n') + ".ply"), "longer than 255 bytes");
  fs::permissions(dir / "locked", fs::perms(0755));
  check_output_path((dir / "ok.ply").string());
  check_output_path("/dev/null");
  EXPECT_TRUE(is_stream_output("/dev/null"));
  EXPECT_FALSE(is_stream_output((dir / "ok.ply").string()));
  // Collisions, through other spellings and links.
  put(dir / "in.ply", "x");
  fs::create_symlink(dir / "in.ply", dir / "alias.ply");
  EXPECT_TRUE(same_file((dir / "in.ply").string(), (dir / "folder" / ".." / "in.ply").string()));
  EXPECT_TRUE(same_file((dir / "in.ply").string(), (dir / "alias.ply").string()));
  EXPECT_TRUE(same_file((dir / "new.ply").string(), (dir / "folder" / ".." / "new.ply").string()));
  EXPECT_FALSE(same_file((dir / "in.ply").string(), (dir / "new.ply").string()));
  // Mesh names: the extension decides, a device or FIFO without one gets PLY.
  PM_EXPECT_ERROR(mesh_output_format((dir / "o.txt").string()), Status::InvalidArgument, "use .ply, .obj, .vtk, .vtu or .vtp");
  EXPECT_EQ(mesh_output_format("/dev/null"), MeshFormat::PlyBinary);
  EXPECT_EQ(mesh_output_format((dir / "o.obj").string()), MeshFormat::Obj);
}
