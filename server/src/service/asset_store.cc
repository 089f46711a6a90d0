#include "service/asset_store.h"

#include <openssl/evp.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <fstream>
#include <sstream>
#include <system_error>
#include <vector>

#include "service/limits.h"
#include "service/state_folder.h"
#include "service/user_files.h"
#include "yarf/error.h"

namespace yarf {
namespace {

namespace fs = std::filesystem;

// Temporary files older than this belong to no upload still running.
constexpr auto kStaleTemp = std::chrono::hours(1);

[[noreturn]] void ThrowErrno(const std::string& what) {
  throw std::system_error(errno, std::generic_category(), what);
}

void RemoveStaleTemps(const fs::path& folder) {
  std::error_code ec;
  const auto now = fs::file_time_type::clock::now();
  for (const fs::directory_entry& entry : fs::directory_iterator(folder, ec)) {
    const auto written = entry.last_write_time(ec);
    if (!ec && now - written > kStaleTemp) fs::remove(entry.path(), ec);
  }
}

}  // namespace

AssetStore::AssetStore(fs::path root, uint64_t max_bytes_per_user)
    : root_(std::move(root)), max_bytes_per_user_(max_bytes_per_user) {
  fs::create_directories(TempFolder());
  RemoveStaleTemps(TempFolder());
}

fs::path AssetStore::PathOf(const std::string& sha256) const { return root_ / sha256.substr(0, 2) / sha256; }

bool AssetStore::Has(const std::string& sha256) const {
  std::error_code ec;
  return IsSha256(sha256) && fs::is_regular_file(PathOf(sha256), ec);
}

fs::path AssetStore::FileOf(const std::string& sha256) const {
  if (!Has(sha256)) throw Error("asset '" + sha256.substr(0, 80) + "' is not on this server; upload it first");
  return PathOf(sha256);
}

std::string AssetStore::Read(const std::string& sha256) const {
  if (!IsSha256(sha256))
    throw Error("asset '" + sha256.substr(0, 80) + "' is not a SHA-256 (64 lowercase hex digits)");
  std::ifstream in(PathOf(sha256), std::ios::binary);
  if (!in) throw Error("asset " + sha256 + " is not on this server; upload it first");
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return std::move(bytes).str();
}

bool AssetStore::Owns(const std::string& sha256, const std::string& user) const {
  std::error_code ec;
  return Has(sha256) && fs::exists(OwnersOf(sha256) / UserFolderName(user), ec);
}

void AssetStore::Touch(const std::string& sha256, const std::string& user) const {
  std::error_code ignored;  // a mark of use only
  fs::last_write_time(OwnersOf(sha256) / UserFolderName(user), fs::file_time_type::clock::now(), ignored);
}

uint64_t AssetStore::HeldBy(const std::string& user) const {
  const std::string name = UserFolderName(user);
  uint64_t held = 0;
  std::error_code ec;
  for (const fs::directory_entry& owners : fs::directory_iterator(root_ / "owners", ec))
    if (fs::exists(owners.path() / name, ec))
      if (const uintmax_t size = fs::file_size(PathOf(owners.path().filename().string()), ec); !ec) held += size;
  return held;
}

std::unique_ptr<AssetStore::Reservation> AssetStore::Reserve(const std::string& sha256, const std::string& user,
                                                             uint64_t size) const {
  if (Owns(sha256, user)) size = 0;  // theirs already: nothing more held
  std::lock_guard lock(mutex_);
  const uint64_t held = HeldBy(user), uploading = uploading_[user];
  if (held + uploading + size > max_bytes_per_user_)
    throw LimitReached(user + " holds " + std::to_string(held >> 20) + " MiB of assets and uploads " +
                       std::to_string(uploading >> 20) + " MiB; " + std::to_string(size >> 20) +
                       " MiB more is past the " + std::to_string(max_bytes_per_user_ >> 20) +
                       " MiB one user may (yarfd --max-asset-bytes-per-user); unused ones go after "
                       "--asset-grace-hours");
  uploading_[user] += size;
  return std::make_unique<Reservation>(*this, user, size);
}

AssetStore::Reservation::~Reservation() {
  std::lock_guard lock(store_.mutex_);
  if ((store_.uploading_[user_] -= bytes_) == 0) store_.uploading_.erase(user_);
}

size_t AssetStore::CollectGarbage(const std::set<std::string>& in_use, std::chrono::seconds grace) const {
  const auto cutoff = fs::file_time_type::clock::now() - grace;
  size_t removed = 0;
  std::error_code ec;
  for (const fs::directory_entry& prefix : fs::directory_iterator(root_, ec)) {
    const std::string folder = prefix.path().filename().string();
    if (folder.size() != 2 || !prefix.is_directory(ec)) continue;  // tmp/, owners/
    for (const fs::directory_entry& asset : fs::directory_iterator(prefix.path(), ec)) {
      const std::string hash = asset.path().filename().string();
      if (!IsSha256(hash) || in_use.contains(hash)) continue;
      // Last used: the newest mark of an owner, else the file itself.
      auto used = asset.last_write_time(ec);
      for (const fs::directory_entry& owner : fs::directory_iterator(OwnersOf(hash), ec))
        used = std::max(used, owner.last_write_time(ec));
      if (used > cutoff) continue;
      fs::remove(asset.path(), ec);
      fs::remove_all(OwnersOf(hash), ec);
      ++removed;
    }
  }
  return removed;
}

void AssetStore::AddOwner(const std::string& sha256, const std::string& user) const {
  const fs::path folder = OwnersOf(sha256);
  const bool new_folder = fs::create_directories(folder);
  const fs::path marker = folder / UserFolderName(user);
  if (fs::exists(marker)) return Touch(sha256, user);
  std::ofstream(marker).close();
  if (!fs::exists(marker)) throw Error("cannot record the owner of asset " + sha256 + " in " + folder.string());
  // Synced as the asset itself is: an upload reported done stays the user's.
  for (const fs::path& synced : new_folder ? std::vector{folder, folder.parent_path()} : std::vector{folder})
    if (const std::error_code error = SyncFolder(synced))
      throw Error("cannot sync " + synced.string() + ": " + error.message());
}

std::string UserAssets::Read(const std::string& sha256) const {
  if (!Has(sha256)) throw Error("asset " + sha256 + " is not on this server; upload it first");
  return store_.Read(sha256);
}

fs::path UserAssets::FileOf(const std::string& sha256) const {
  if (!Has(sha256)) throw Error("asset " + sha256 + " is not on this server; upload it first");
  return store_.FileOf(sha256);
}

void AssetUpload::DigestFree::operator()(evp_md_ctx_st* context) const { EVP_MD_CTX_free(context); }

AssetUpload::AssetUpload(const AssetStore& store, std::string sha256, uint64_t size)
    : store_(store), sha256_(std::move(sha256)), size_(size), digest_(EVP_MD_CTX_new()) {
  if (!IsSha256(sha256_))
    throw Error("asset hash '" + sha256_.substr(0, 80) + "' is not a SHA-256 (64 lowercase hex digits)");
  if (size_ > AssetStore::kMaxSize)
    throw Error("asset " + sha256_ + " has " + std::to_string(size_) + " bytes; at most " +
                std::to_string(AssetStore::kMaxSize) + " (2 GiB) are allowed");
  if (!digest_ || EVP_DigestInit_ex(digest_.get(), EVP_sha256(), nullptr) != 1)
    throw std::runtime_error("cannot start a SHA-256 digest");
  if (store_.Has(sha256_)) return;
  // A file of its own per upload: concurrent uploads of one hash never
  // write into each other.
  std::string name = (store_.TempFolder() / (sha256_ + ".XXXXXX")).string();
  const int fd = mkstemp(name.data());
  if (fd < 0) ThrowErrno("cannot create a temporary file in " + store_.TempFolder().string());
  temp_path_ = name;
  file_.reset(fdopen(fd, "wb"));
  if (!file_) {
    const int error = errno;
    close(fd);
    throw std::system_error(error, std::generic_category(), "cannot open " + name);
  }
}

AssetUpload::~AssetUpload() {
  file_.reset();
  std::error_code ec;
  if (!temp_path_.empty()) fs::remove(temp_path_, ec);
}

void AssetUpload::Append(std::string_view bytes) {
  if (bytes.size() > size_ - received_)
    throw Error("asset " + sha256_ + ": more bytes arrived than the " + std::to_string(size_) + " announced");
  received_ += bytes.size();
  if (EVP_DigestUpdate(digest_.get(), bytes.data(), bytes.size()) != 1)
    throw std::runtime_error("SHA-256 digest failed");
  if (file_ && std::fwrite(bytes.data(), 1, bytes.size(), file_.get()) != bytes.size())
    ThrowErrno("cannot write " + temp_path_.string());
}

std::string AssetUpload::HexDigest() {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  if (EVP_DigestFinal_ex(digest_.get(), digest, &length) != 1) throw std::runtime_error("SHA-256 digest failed");
  static constexpr char kHex[] = "0123456789abcdef";
  std::string hex;
  for (unsigned int i = 0; i < length; ++i) {
    hex += kHex[digest[i] >> 4];
    hex += kHex[digest[i] & 15];
  }
  return hex;
}

bool AssetUpload::Commit() {
  if (received_ != size_)
    throw Error("asset " + sha256_ + ": " + std::to_string(received_) + " bytes arrived, " +
                std::to_string(size_) + " were announced");
  const std::string actual = HexDigest();
  if (actual != sha256_) throw Error("asset " + sha256_ + ": the bytes that arrived hash to " + actual);
  if (!file_) return false;
  // On disk before it has a name: a crash never leaves a short asset.
  if (std::fflush(file_.get()) != 0 || fsync(fileno(file_.get())) != 0)
    ThrowErrno("cannot write " + temp_path_.string());
  file_.reset();
  const fs::path target = store_.PathOf(sha256_);
  const bool new_folder = fs::create_directories(target.parent_path());
  // A link, unlike a rename, fails when the name exists: of two uploads of
  // the same bytes at once, exactly one reports that it stored them.
  std::error_code ec;
  fs::create_hard_link(temp_path_, target, ec);
  const bool stored = ec != std::errc::file_exists;
  // A file system without hard links: replacing the same bytes is harmless.
  if (ec && stored) fs::rename(temp_path_, target);
  fs::remove(temp_path_, ec);
  temp_path_.clear();
  // The new name (and a new folder's) on disk before the upload is
  // reported stored: else a power loss could lose an asset jobs rely on.
  const auto sync = [](const fs::path& folder) {
    if (const std::error_code synced = SyncFolder(folder))
      throw std::system_error(synced, "cannot sync " + folder.string());
  };
  sync(target.parent_path());
  if (new_folder) sync(store_.root());
  return stored;
}

}  // namespace yarf
