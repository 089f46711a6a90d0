// yarf.v1.AssetService over the asset store: which assets are missing, and
// uploads in chunks.
#pragma once

#include "service/asset_store.h"
#include "yarf/v1/asset.grpc.pb.h"

namespace yarf {

class AssetServiceImpl final : public v1::AssetService::Service {
 public:
  static constexpr size_t kMaxChunk = size_t(4) << 20;  // 4 MiB
  // Hashes one Missing call may ask about.
  static constexpr int kMaxHashes = 100'000;

  explicit AssetServiceImpl(AssetStore& store) : store_(store) {}

  grpc::Status Missing(grpc::ServerContext*, const v1::MissingAssetsRequest*, v1::MissingAssetsReply*) override;
  grpc::Status Upload(grpc::ServerContext*, grpc::ServerReader<v1::AssetChunk>*, v1::UploadAssetReply*) override;

 private:
  AssetStore& store_;
};

}  // namespace yarf
