#include "service/asset_store.h"

#include <dlfcn.h>
#include <gtest/gtest.h>
#include <openssl/evp.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <mutex>
#include <vector>

namespace {

// Folders fsync was called on, recorded by the fsync below.
std::mutex synced_mutex;
std::vector<std::filesystem::path> synced_folders;

}  // namespace

// Stands in for libc's fsync in this binary (and the code it tests), so a
// test can see which folders were synced; then calls the real one.
extern "C" int fsync(int fd) {
  using Fsync = int (*)(int);
  static const auto real = reinterpret_cast<Fsync>(dlsym(RTLD_NEXT, "fsync"));
  struct stat info;
  if (::fstat(fd, &info) == 0 && S_ISDIR(info.st_mode)) {
    std::error_code ec;
    const auto path = std::filesystem::read_symlink("/proc/self/fd/" + std::to_string(fd), ec);
    std::lock_guard lock(synced_mutex);
    if (!ec) synced_folders.push_back(path);
  }
  return real(fd);
}

namespace yarf {
namespace {

std::string Sha256(const std::string& bytes) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_Digest(bytes.data(), bytes.size(), digest, &length, EVP_sha256(), nullptr);
  std::string hex;
  for (unsigned int i = 0; i < length; ++i) {
    static constexpr char kHex[] = "0123456789abcdef";
    hex += kHex[digest[i] >> 4];
    hex += kHex[digest[i] & 15];
  }
  return hex;
}

bool Synced(const std::filesystem::path& folder) {
  const auto wanted = std::filesystem::canonical(folder);
  std::lock_guard lock(synced_mutex);
  return std::find(synced_folders.begin(), synced_folders.end(), wanted) != synced_folders.end();
}

TEST(AssetUpload, AStoredAssetsNameAndNewFolderAreSyncedBeforeCommitReturns) {
  std::string pattern = (std::filesystem::temp_directory_path() / "yarf-assets-XXXXXX").string();
  const std::filesystem::path folder = ::mkdtemp(pattern.data());
  {
    AssetStore store(folder / "assets");
    const std::string bytes = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    const std::string sha256 = Sha256(bytes);
    {
      std::lock_guard lock(synced_mutex);
      synced_folders.clear();
    }
    AssetUpload upload(store, sha256, bytes.size());
    upload.Append(bytes);
    ASSERT_TRUE(upload.Commit());
    EXPECT_TRUE(store.Has(sha256));
    // A power loss now must not lose the asset's name, nor its new folder's.
    EXPECT_TRUE(Synced(store.PathOf(sha256).parent_path())) << "the asset's folder was not synced";
    EXPECT_TRUE(Synced(store.root())) << "the store's folder, which gained a folder, was not synced";
  }
  std::filesystem::remove_all(folder);
}

}  // namespace
}  // namespace yarf
