#include <pcl_fot/io/file_io.h>

#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

namespace pcl {
namespace fot {
namespace io {

namespace {
[[noreturn]] void fail(const std::string& what, const std::string& path, int err) {
  throw std::runtime_error("pcl::fot::io: cannot " + what + " '" + path + "': " + std::strerror(err));
}

/** Writes all of `bytes` to fd; the errno of a failure, or 0. */
int writeAll(int fd, const std::string& bytes) {
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return n < 0 ? errno : EIO;
    done += std::size_t(n);
  }
  return 0;
}

/** A device or pipe, written as a stream. O_NONBLOCK only to open: a pipe without a reader must not hang. */
void writeStream(const std::string& path, const std::string& bytes) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) fail("open", path, errno);
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);
  const int written = writeAll(fd, bytes);
  const int closed = ::close(fd) == 0 ? 0 : errno;
  if (written || closed) fail("write", path, written ? written : closed);
}

/** The folder and name of a path: "a/b.fot" -> "a", "b.fot". */
void splitPath(const std::string& path, std::string& dir, std::string& name) {
  const std::size_t slash = path.find_last_of('/');
  dir = slash == std::string::npos ? "." : slash == 0 ? "/" : path.substr(0, slash);
  name = slash == std::string::npos ? path : path.substr(slash + 1);
}

/** Removes the temporary files of `name` in `dir` whose writer is no longer alive. */
void removeStaleTemporaries(const std::string& dir, const std::string& name) {
  const std::string prefix = "." + name + ".pcl_fot-tmp.";
  DIR* d = ::opendir(dir.c_str());
  if (!d) return;
  while (const dirent* e = ::readdir(d)) {
    const std::string entry = e->d_name;
    if (entry.compare(0, prefix.size(), prefix) != 0) continue;
    char* end = nullptr;
    const long pid = std::strtol(entry.c_str() + prefix.size(), &end, 10);
    if (pid <= 0 || *end != '.') continue;
    if (::kill(pid_t(pid), 0) != 0 && errno == ESRCH) ::unlink((dir + "/" + entry).c_str());
  }
  ::closedir(d);
}

}  // namespace

void writeFileAtomically(const std::string& path, const std::string& bytes) {
  std::string target = path;
  struct stat st;
  if (::stat(path.c_str(), &st) == 0) {
    if (S_ISDIR(st.st_mode)) fail("write", path, EISDIR);
    if (!S_ISREG(st.st_mode)) {
      writeStream(path, bytes);
      return;
    }
    // Through a link, the temporary file goes beside the file it names, and the link stays.
    if (char* real = ::realpath(path.c_str(), nullptr)) {
      target = real;
      std::free(real);
    }
  }
  std::string dir, name;
  splitPath(target, dir, name);
  removeStaleTemporaries(dir, name);
  // Unique per process and per call, so that threads saving the same path do not share a temporary file.
  static std::atomic<std::uint64_t> calls{0};
  const std::string tmp =
      dir + "/." + name + ".pcl_fot-tmp." + std::to_string(::getpid()) + "." + std::to_string(calls++);
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) fail("create", tmp, errno);
  const int written = writeAll(fd, bytes);
  if (written) {
    ::close(fd);
    std::remove(tmp.c_str());
    fail("write", tmp, written);
  }
  const int synced = ::fsync(fd) == 0 ? 0 : errno;
  const int closed = ::close(fd) == 0 ? 0 : errno;
  if (synced || closed) {
    std::remove(tmp.c_str());
    fail("flush", tmp, synced ? synced : closed);
  }
  if (std::rename(tmp.c_str(), target.c_str()) != 0) {
    const int err = errno;
    std::remove(tmp.c_str());
    fail("rename to", target, err);
  }
}

std::string readFile(const std::string& path, std::size_t max_bytes) {
  // O_NONBLOCK: opening a FIFO without a writer would wait for one.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) fail("open", path, errno);
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st;
  if (::fstat(fd, &st) != 0) fail("read", path, errno);
  // A device, pipe or directory has no size to check against max_bytes, and /dev/zero has no end.
  if (!S_ISREG(st.st_mode)) throw std::runtime_error("pcl::fot::io: '" + path + "' is not a regular file");
  const std::uint64_t size = std::uint64_t(st.st_size);
  if (size > max_bytes)
    throw std::length_error("pcl::fot::io: '" + path + "' has " + std::to_string(size) +
                            " bytes, more than the " + std::to_string(max_bytes) +
                            " a valid file of its kind can have here");
  std::string bytes(std::size_t(size), '\0');
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::read(fd, &bytes[done], bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) fail("read", path, errno);
    if (n == 0) fail("read", path, EIO);  // shorter than its size: it changed while read
    done += std::size_t(n);
  }
  return bytes;
}

}  // namespace io
}  // namespace fot
}  // namespace pcl
