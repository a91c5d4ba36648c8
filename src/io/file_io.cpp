#include <pcl_fot/io/file_io.h>

#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace pcl {
namespace fot {
namespace io {

namespace {
[[noreturn]] void fail(const std::string& what, const std::string& path, int err) {
  throw std::runtime_error("pcl::fot::io: cannot " + what + " '" + path + "': " + std::strerror(err));
}
}  // namespace

void writeFileAtomically(const std::string& path, const std::string& bytes) {
  // Unique per process and per call, so that threads saving the same path do not share a temporary file.
  static std::atomic<std::uint64_t> calls{0};
  const std::string tmp = path + ".tmp" + std::to_string(::getpid()) + "." + std::to_string(calls++);
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) fail("create", tmp, errno);
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = errno;
      ::close(fd);
      std::remove(tmp.c_str());
      fail("write", tmp, err);
    }
    done += std::size_t(n);
  }
  const int synced = ::fsync(fd) == 0 ? 0 : errno;
  const int closed = ::close(fd) == 0 ? 0 : errno;
  if (synced || closed) {
    std::remove(tmp.c_str());
    fail("flush", tmp, synced ? synced : closed);
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    std::remove(tmp.c_str());
    fail("rename to", path, err);
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
