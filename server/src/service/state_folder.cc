#include "service/state_folder.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <utility>

#include "yarf/error.h"

namespace yarf {
namespace {

std::string SystemError() { return std::strerror(errno); }

// Closes a descriptor when it goes out of scope.
class Descriptor {
 public:
  explicit Descriptor(int fd) : fd_(fd) {}
  ~Descriptor() {
    if (fd_ >= 0) ::close(fd_);
  }
  Descriptor(const Descriptor&) = delete;
  Descriptor& operator=(const Descriptor&) = delete;
  int get() const { return fd_; }
  int release() { return std::exchange(fd_, -1); }

 private:
  int fd_;
};

}  // namespace

std::error_code SyncFolder(const std::filesystem::path& folder) {
  Descriptor fd(::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC));
  if (fd.get() < 0) return {errno, std::generic_category()};
  // EINVAL: a file system that cannot sync folders; there is nothing more to do.
  if (::fsync(fd.get()) != 0 && errno != EINVAL) return {errno, std::generic_category()};
  return {};
}

StateFolder::StateFolder(std::filesystem::path root) : root_(std::move(root)) {
  std::error_code error;
  for (const auto& folder : {root_, Checkpoints(), Results()}) {
    std::filesystem::create_directories(folder, error);
    if (error) throw Error("cannot create the state folder " + folder.string() + ": " + error.message());
  }
  const std::filesystem::path lock = root_ / "lock";
  Descriptor fd(::open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644));
  if (fd.get() < 0) throw Error("cannot write in the state folder " + root_.string() + ": " + SystemError());
  // The lock goes with the process, however it ends: a kill -9 frees it.
  if (::flock(fd.get(), LOCK_EX | LOCK_NB) != 0) {
    if (errno == EWOULDBLOCK)
      throw Error("another yarfd is using the state folder " + root_.string() + " (" + lock.string() +
                  " is locked); stop it or give this one another --state-dir");
    throw Error("cannot lock " + lock.string() + ": " + SystemError());
  }
  // Written for people who wonder which process holds it.
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (::ftruncate(fd.get(), 0) != 0 || ::pwrite(fd.get(), pid.data(), pid.size(), 0) != ssize_t(pid.size()))
    throw Error("cannot write in the state folder " + root_.string() + ": " + SystemError());
  lock_fd_ = fd.release();
}

StateFolder::~StateFolder() {
  if (lock_fd_ >= 0) ::close(lock_fd_);
}

std::string StateFolder::DescribeJobFiles() const {
  auto count = [](const std::filesystem::path& folder) {
    size_t files = 0;
    std::error_code error;
    for (const auto& entry : std::filesystem::directory_iterator(folder, error))
      if (entry.path().extension() != ".tmp") ++files;
    return files;
  };
  const size_t results = count(Results()), checkpoints = count(Checkpoints());
  if (results + checkpoints == 0) return "";
  auto files = [](size_t n) { return std::to_string(n) + (n == 1 ? " file" : " files"); };
  return files(results) + " in " + Results().string() + " and " + files(checkpoints) + " in " +
         Checkpoints().string();
}

void WriteFileAtomically(const std::filesystem::path& path, std::string_view bytes) {
  const std::filesystem::path temporary = path.string() + ".tmp";
  {
    Descriptor fd(::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644));
    if (fd.get() < 0) throw Error("cannot write " + temporary.string() + ": " + SystemError());
    for (size_t written = 0; written < bytes.size();) {
      const ssize_t n = ::write(fd.get(), bytes.data() + written, bytes.size() - written);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) throw Error("cannot write " + temporary.string() + ": " + SystemError());
      written += size_t(n);
    }
    if (::fsync(fd.get()) != 0) throw Error("cannot write " + temporary.string() + ": " + SystemError());
  }
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) throw Error("cannot rename " + temporary.string() + ": " + error.message());
  if (const std::error_code synced = SyncFolder(path.parent_path()))
    throw Error("cannot sync the folder of " + path.string() + ": " + synced.message());
}

std::optional<std::string> ReadWholeFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    if (!std::filesystem::exists(path)) return std::nullopt;
    throw Error("cannot read " + path.string());
  }
  std::ostringstream bytes;
  bytes << in.rdbuf();
  if (in.bad()) throw Error("cannot read " + path.string());
  return std::move(bytes).str();
}

}  // namespace yarf
