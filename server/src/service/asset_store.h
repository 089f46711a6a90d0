// Uploaded assets on disk, named by content: <root>/<first 2 hex>/<sha256>,
// root being <state_dir>/assets, so they outlive the server. An upload
// streams into a temporary file of its own, is checked against the hash
// and size it announced, and only then appears under its name: a reader
// never sees part of an asset, and uploads of the same bytes, even at the
// same time, keep one file.
//
// Each asset is held for the users who uploaded it (<root>/owners/<sha256>/
// has a file per user): to anyone else it is missing, so that Missing
// cannot tell who uploaded what and no job uses bytes its user never had.
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <string_view>

#include "components/scene_builder.h"

struct evp_md_ctx_st;

namespace yarf {

class AssetStore final : public AssetSource {
 public:
  static constexpr uint64_t kMaxSize = uint64_t(2) << 30;  // 2 GiB

  // Creates the folders (throws std::filesystem::filesystem_error when it
  // cannot) and drops temporary files that crashed uploads left behind.
  // A user holds at most `max_bytes_per_user` of assets.
  explicit AssetStore(std::filesystem::path root, uint64_t max_bytes_per_user = uint64_t(20) << 30);

  bool Has(const std::string& sha256) const override;
  std::string Read(const std::string& sha256) const override;
  std::filesystem::path FileOf(const std::string& sha256) const override;

  // Whether `user` uploaded the asset (and it is held).
  bool Owns(const std::string& sha256, const std::string& user) const;
  // Records that `user` uploaded the asset, durably; a mark of use, which
  // keeps it from collection for a while (CollectGarbage).
  void AddOwner(const std::string& sha256, const std::string& user) const;
  // Marks the asset as used by `user` now (when they ask for it in Missing).
  void Touch(const std::string& sha256, const std::string& user) const;
  // Room for an upload in `user`'s share, held while the upload runs, so
  // that uploads at once cannot pass it together.
  class Reservation {
   public:
    Reservation(const AssetStore& store, std::string user, uint64_t bytes)
        : store_(store), user_(std::move(user)), bytes_(bytes) {}
    ~Reservation();
    Reservation(const Reservation&) = delete;
    Reservation& operator=(const Reservation&) = delete;

   private:
    const AssetStore& store_;
    const std::string user_;
    const uint64_t bytes_;
  };
  // Throws LimitReached when `user` uploading `size` more bytes of an asset
  // not theirs yet would, with their uploads running, hold more than
  // their share.
  std::unique_ptr<Reservation> Reserve(const std::string& sha256, const std::string& user, uint64_t size) const;
  // Removes the assets that no hash of `in_use` names and nobody has
  // uploaded or asked for in the last `grace`; returns how many went.
  size_t CollectGarbage(const std::set<std::string>& in_use, std::chrono::seconds grace) const;

  const std::filesystem::path& root() const { return root_; }
  std::filesystem::path OwnersOf(const std::string& sha256) const { return root_ / "owners" / sha256; }
  // Where the asset named `sha256` (already checked) lives.
  std::filesystem::path PathOf(const std::string& sha256) const;
  std::filesystem::path TempFolder() const { return root_ / "tmp"; }

 private:
  // Bytes of the assets `user` holds.
  uint64_t HeldBy(const std::string& user) const;

  const std::filesystem::path root_;
  const uint64_t max_bytes_per_user_;
  mutable std::mutex mutex_;
  // Bytes of uploads running, by user.
  mutable std::map<std::string, uint64_t> uploading_;
};

// The assets of one user, as the kernel reads them for that user's jobs.
class UserAssets final : public AssetSource {
 public:
  UserAssets(const AssetStore& store, std::string user) : store_(store), user_(std::move(user)) {}
  bool Has(const std::string& sha256) const override { return store_.Owns(sha256, user_); }
  std::string Read(const std::string& sha256) const override;
  std::filesystem::path FileOf(const std::string& sha256) const override;

 private:
  const AssetStore& store_;
  std::string user_;
};

// One asset arriving in pieces. Destroyed without a successful Commit, it
// leaves nothing behind.
class AssetUpload {
 public:
  // Throws Error for a hash that is not 64 lowercase hex digits or a size
  // over AssetStore::kMaxSize.
  AssetUpload(const AssetStore& store, std::string sha256, uint64_t size);
  ~AssetUpload();
  AssetUpload(const AssetUpload&) = delete;
  AssetUpload& operator=(const AssetUpload&) = delete;

  // The next bytes; throws Error once they pass the announced size.
  void Append(std::string_view bytes);
  // Checks the size and the hash of what arrived (Error when either
  // differs), then puts the asset in place. False when the store held it
  // already.
  bool Commit();

 private:
  struct FileCloser {
    void operator()(std::FILE* file) const { std::fclose(file); }
  };
  struct DigestFree {
    void operator()(evp_md_ctx_st* context) const;
  };

  std::string HexDigest();

  const AssetStore& store_;
  const std::string sha256_;
  const uint64_t size_;
  uint64_t received_ = 0;
  std::unique_ptr<evp_md_ctx_st, DigestFree> digest_;
  // Null when the store holds the asset already: the bytes are then only
  // hashed, to answer truthfully, and dropped.
  std::unique_ptr<std::FILE, FileCloser> file_;
  std::filesystem::path temp_path_;
};

}  // namespace yarf
