#include "particlemesh/io/output_file.h"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <string>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>

#include "particlemesh/core/error.h"
#include "particlemesh/io/atomic_write.h"

namespace PM_NAMESPACE {

namespace {

// ---- the temporaries a signal handler removes ------------------------------------------
// A fixed table (no allocation, no lock): a slot is claimed (1), filled, then published (2);
// the handler unlinks the published ones. More outputs than slots at once only lose the
// clean-up on a signal, nothing else.
constexpr int kSlots = 64;
struct Slot {
  std::atomic<int> state{0};
  char path[PATH_MAX];
};
Slot g_slots[kSlots];

int register_temporary(const std::string& path) {
  if (path.size() >= PATH_MAX) return -1;
  for (int i = 0; i < kSlots; ++i) {
    int expected = 0;
    if (g_slots[i].state.compare_exchange_strong(expected, 1)) {
      std::memcpy(g_slots[i].path, path.c_str(), path.size() + 1);
      g_slots[i].state.store(2, std::memory_order_release);
      return i;
    }
  }
  return -1;
}

void unregister_temporary(int slot) {
  if (slot >= 0) g_slots[slot].state.store(0, std::memory_order_release);
}

std::string error_text(int e) { return std::strerror(e); }

[[noreturn]] void io_error(const std::string& path, const std::string& why) {
  throw Error(Status::IoError, "cannot write '" + path + "': " + why);
}

// ---- resolving the path ------------------------------------------------------------------

/// fd of a standard-stream name (/dev/stdout, /dev/stderr, /dev/fd/N, /proc/self/fd/N), or -1.
int stream_name_fd(const std::string& path) {
  if (path == "/dev/stdout") return 1;
  if (path == "/dev/stderr") return 2;
  for (const char* prefix : {"/dev/fd/", "/proc/self/fd/"}) {
    const size_t n = std::strlen(prefix);
    if (path.compare(0, n, prefix) == 0 && path.size() > n && path.size() < n + 6) {
      int fd = 0;
      for (size_t i = n; i < path.size(); ++i) {
        if (path[i] < '0' || path[i] > '9') return -1;
        fd = fd * 10 + (path[i] - '0');
      }
      return fd;
    }
  }
  return -1;
}

std::string parent_of(const std::string& p) {
  const size_t slash = p.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return p.substr(0, slash);
}

std::string name_of(const std::string& p) {
  const size_t slash = p.find_last_of('/');
  return slash == std::string::npos ? p : p.substr(slash + 1);
}

/// Follow symbolic links at the path's last component (the folders on the way are the
/// kernel's business): the file that will be written. Throws `Status` on a loop.
std::string resolve_links(const std::string& path, Status status) {
  std::string p = path;
  for (int hops = 0; hops < 40; ++hops) {
    struct stat st {};
    if (::lstat(p.c_str(), &st) != 0 || !S_ISLNK(st.st_mode)) return p;
    std::vector<char> buf(size_t(st.st_size > 0 ? st.st_size : PATH_MAX) + 1);
    const ssize_t n = ::readlink(p.c_str(), buf.data(), buf.size() - 1);
    if (n < 0) return p;
    const std::string target(buf.data(), size_t(n));
    p = !target.empty() && target[0] == '/' ? target : (parent_of(p) == "." && p.find('/') == std::string::npos ? target : parent_of(p) + "/" + target);
  }
  throw Error(status, "'" + path + "': too many levels of symbolic links");
}

char random_char(uint64_t& bits) {
  static const char kAlphabet[] = "abcdefghijklmnopqrstuvwxyz0123456789";
  const char c = kAlphabet[bits % 36];
  bits /= 36;
  return c;
}

uint64_t random_bits() {
  uint64_t v = 0;
  if (::getrandom(&v, sizeof v, GRND_NONBLOCK) != ssize_t(sizeof v)) {
    static std::atomic<uint64_t> counter{0};
    v = (uint64_t(::getpid()) << 32) ^ uint64_t(reinterpret_cast<uintptr_t>(&v)) ^ (counter++ * 0x9E3779B97F4A7C15ull) ^
        uint64_t(::time(nullptr));
  }
  return v;
}

bool write_all(int fd, const char* data, size_t size, int* error) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      *error = errno;
      return false;
    }
    data += n;
    size -= size_t(n);
  }
  return true;
}

}  // namespace

void remove_unfinished_outputs() noexcept {
  for (Slot& s : g_slots)
    if (s.state.load(std::memory_order_acquire) == 2) ::unlink(s.path);
}

bool is_stream_output(const std::string& path) {
  if (stream_name_fd(path) >= 0) return true;
  std::string target;
  try {
    target = resolve_links(path, Status::InvalidArgument);
  } catch (const Error&) {
    return false;
  }
  struct stat st {};
  return ::stat(target.c_str(), &st) == 0 && !S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode);
}

void check_output_path(const std::string& path) {
  auto bad = [&](const std::string& why) { throw Error(Status::InvalidArgument, "output '" + path + "': " + why); };
  if (path.empty()) throw Error(Status::InvalidArgument, "an output path is empty");
  if (const int fd = stream_name_fd(path); fd >= 0) {
    if (::fcntl(fd, F_GETFD) < 0) bad("the process has no file descriptor " + std::to_string(fd));
    return;
  }
  const std::string target = resolve_links(path, Status::InvalidArgument);
  if (name_of(target).empty() || name_of(target) == "." || name_of(target) == "..") bad("names a folder, not a file");
  if (name_of(target).size() > NAME_MAX) bad("the file name is longer than " + std::to_string(NAME_MAX) + " bytes");
  struct stat st {};
  const bool exists = ::stat(target.c_str(), &st) == 0;
  if (exists) {
    if (S_ISDIR(st.st_mode)) bad("is a folder");
    if (!S_ISREG(st.st_mode)) {
      if (::access(target.c_str(), W_OK) != 0) bad("cannot be written: " + error_text(errno));
      return;
    }
    if ((st.st_mode & 0222) == 0) bad("the file is read-only (no write permission)");
    if (::access(target.c_str(), W_OK) != 0) bad("the file is not writable: " + error_text(errno));
    if (st.st_nlink > 1) return;  // rewritten in place (see OutputFile): no temporary in the folder
  } else if (errno != ENOENT) {
    bad(error_text(errno));
  }
  const std::string folder = parent_of(target);
  struct stat fs {};
  if (::stat(folder.c_str(), &fs) != 0) {
    if (errno == ENOENT) bad("the folder '" + folder + "' does not exist");
    bad("the folder '" + folder + "': " + error_text(errno));
  }
  if (!S_ISDIR(fs.st_mode)) bad("'" + folder + "' is not a folder");
  if ((fs.st_mode & 0222) == 0) bad("the folder '" + folder + "' is read-only (no write permission)");
  if (::access(folder.c_str(), W_OK | X_OK) != 0) bad("the folder '" + folder + "' is not writable: " + error_text(errno));
}

bool same_file(const std::string& a, const std::string& b) {
  if (a == b) return true;
  std::string ra, rb;
  try {
    ra = resolve_links(a, Status::InvalidArgument);
    rb = resolve_links(b, Status::InvalidArgument);
  } catch (const Error&) {
    return false;
  }
  struct stat sa {}, sb {};
  const bool ea = ::stat(ra.c_str(), &sa) == 0, eb = ::stat(rb.c_str(), &sb) == 0;
  if (ea && eb) return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
  if (ea != eb) return false;
  // Neither exists yet: the same name in the same folder?
  if (name_of(ra) != name_of(rb)) return false;
  struct stat fa {}, fb {};
  return ::stat(parent_of(ra).c_str(), &fa) == 0 && ::stat(parent_of(rb).c_str(), &fb) == 0 &&
         fa.st_dev == fb.st_dev && fa.st_ino == fb.st_ino;
}

// ---- OutputFile --------------------------------------------------------------------------

struct OutputFile::State {
  std::string path;     ///< as given
  std::string target;   ///< the file written (links followed)
  std::string temp;     ///< the temporary ("" for a stream)
  int fd = -1;
  int slot = -1;
  bool stream = false;
  bool copy_in = false;  ///< a hard-linked regular file: rewritten in place at commit
  bool replace = false;  ///< an existing regular file is replaced: its mode and owner are kept
  struct stat old {};
  bool finished = false, committed = false, external = false;
  std::vector<char> buffer;

  void flush() {
    if (buffer.empty()) return;
    int e = 0;
    if (!write_all(fd, buffer.data(), buffer.size(), &e)) io_error(path, error_text(e));
    buffer.clear();
  }
  void discard() noexcept {
    if (fd >= 0) ::close(fd);
    fd = -1;
    if (!temp.empty() && !committed) ::unlink(temp.c_str());
    unregister_temporary(slot);
    slot = -1;
  }
};

OutputFile::OutputFile(const std::string& path) : s_(std::make_unique<State>()) {
  State& s = *s_;
  s.path = path;
  if (path.empty()) throw Error(Status::IoError, "cannot write: the output path is empty");
  if (const int fd = stream_name_fd(path); fd >= 0) {
    s.stream = true;
    s.fd = ::fcntl(fd, F_DUPFD_CLOEXEC, 3);
    if (s.fd < 0) io_error(path, "no file descriptor " + std::to_string(fd) + ": " + error_text(errno));
    return;
  }
  s.target = resolve_links(path, Status::IoError);
  struct stat st {};
  if (::stat(s.target.c_str(), &st) == 0) {
    if (S_ISDIR(st.st_mode)) io_error(path, "it is a folder");
    if (!S_ISREG(st.st_mode)) {
      s.stream = true;
      do s.fd = ::open(s.target.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC);
      while (s.fd < 0 && errno == EINTR);
      if (s.fd < 0) io_error(path, error_text(errno));
      return;
    }
    s.replace = true;
    s.old = st;
    s.copy_in = st.st_nlink > 1;
  }
  const std::string folder = parent_of(s.target);
  struct stat fs {};
  if (::stat(folder.c_str(), &fs) != 0 || !S_ISDIR(fs.st_mode))
    io_error(path, "the folder '" + folder + "' does not exist");
  // A new file gets 0666 less the umask (the kernel applies it); a replacement is created
  // private and given the old file's mode once complete.
  const mode_t mode = s.replace ? 0600 : 0666;
  // The target's extension, when short, ends the temporary's name too (a writer that goes
  // by the extension, or a check that reads the file back, sees the same format).
  std::string ext;
  const std::string name_part = name_of(s.target);
  if (const size_t dot = name_part.find_last_of('.'); dot != std::string::npos && dot > 0 && name_part.size() - dot <= 8) {
    ext = name_part.substr(dot);
    for (char c : ext.substr(1))
      if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9'))) ext.clear();
  }
  for (int attempt = 0; attempt < 100; ++attempt) {
    uint64_t bits = random_bits();
    std::string name = ".pm";
    for (int k = 0; k < 10; ++k) name += random_char(bits);
    name += ext;
    const std::string temp = folder == "/" ? "/" + name : folder + "/" + name;
    // Published for the signal handler before the file exists: a signal between the two
    // would otherwise leave the new file behind. Were the name taken (EEXIST), the slot goes
    // at once; the name is random, 60 bits.
    const int slot = register_temporary(temp);
    const int fd = ::open(temp.c_str(), O_RDWR | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, mode);
    if (fd >= 0) {
      s.fd = fd;
      s.temp = temp;
      s.slot = slot;
      return;
    }
    const int e = errno;
    unregister_temporary(slot);
    if (e != EEXIST && e != EINTR) io_error(path, error_text(e));
  }
  io_error(path, "could not create a temporary file in '" + folder + "'");
}

OutputFile::~OutputFile() { s_->discard(); }

const std::string& OutputFile::path() const { return s_->path; }
bool OutputFile::streams() const { return s_->stream; }

void OutputFile::write(const void* data, size_t size) {
  State& s = *s_;
  if (s.finished || s.fd < 0) throw Error(Status::Internal, "'" + s.path + "' written after it was finished");
  constexpr size_t kBuffer = size_t(1) << 20;
  if (s.buffer.capacity() < kBuffer) s.buffer.reserve(kBuffer);
  const char* p = static_cast<const char*>(data);
  if (size >= kBuffer) {
    s.flush();
    int e = 0;
    if (!write_all(s.fd, p, size, &e)) io_error(s.path, error_text(e));
    return;
  }
  if (s.buffer.size() + size > kBuffer) s.flush();
  s.buffer.insert(s.buffer.end(), p, p + size);
}

std::string OutputFile::path_for_external_writer() {
  State& s = *s_;
  s.external = true;
  if (s.stream) {
    if (s.fd >= 0) ::close(s.fd);
    s.fd = -1;
    return s.target.empty() ? s.path : s.target;
  }
  return s.temp;
}

void OutputFile::finish() {
  State& s = *s_;
  if (s.finished) return;
  if (!s.external) s.flush();
  if (!s.temp.empty() && s.replace && !s.copy_in) {
    // The replaced file's permissions (and owner, where allowed: root, or the same user).
    ::fchmod(s.fd, s.old.st_mode & 07777);
    if (s.old.st_uid != ::geteuid() || s.old.st_gid != ::getegid()) {
      if (::fchown(s.fd, s.old.st_uid, s.old.st_gid) != 0) { /* not permitted: the file becomes ours */ }
    }
  }
  if (s.fd >= 0 && !s.copy_in) {
    const int fd = s.fd;
    s.fd = -1;
    if (::close(fd) != 0 && errno != EINTR) io_error(s.path, error_text(errno));
  }
  s.finished = true;
}

void OutputFile::commit() {
  State& s = *s_;
  finish();
  if (s.committed) return;
  if (s.stream) {
    s.committed = true;
    return;
  }
  if (s.copy_in) {
    // Hard links: the complete contents are in the temporary; copy them into the file itself.
    const int out = ::open(s.target.c_str(), O_WRONLY | O_TRUNC | O_NOFOLLOW | O_CLOEXEC);
    if (out < 0) io_error(s.path, error_text(errno));
    char buf[1 << 16];
    off_t at = 0;
    int e = 0;
    bool ok = true;
    while (ok) {
      const ssize_t n = ::pread(s.fd, buf, sizeof buf, at);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) {
        e = errno;
        ok = false;
        break;
      }
      if (n == 0) break;
      ok = write_all(out, buf, size_t(n), &e);
      at += n;
    }
    if (::close(out) != 0 && ok) {
      e = errno;
      ok = false;
    }
    if (!ok) io_error(s.path, error_text(e) + " (while rewriting the hard-linked file in place; it may be incomplete)");
    s.discard();  // closes and removes the temporary
    s.committed = true;
    return;
  }
  if (::rename(s.temp.c_str(), s.target.c_str()) != 0) io_error(s.path, error_text(errno));
  s.committed = true;
  unregister_temporary(s.slot);
  s.slot = -1;
}

void write_file_atomically(const std::string& path, const std::string& contents) {
  OutputFile out(path);
  out.write(contents);
  out.commit();
}

}  // namespace particlemesh
