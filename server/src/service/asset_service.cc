#include "service/asset_service.h"

#include "service/access.h"
#include "service/limits.h"
#include "yarf/error.h"

namespace yarf {
namespace {

grpc::Status Invalid(const std::string& message) { return {grpc::StatusCode::INVALID_ARGUMENT, message}; }

}  // namespace

grpc::Status AssetServiceImpl::Missing(grpc::ServerContext* context, const v1::MissingAssetsRequest* request,
                                       v1::MissingAssetsReply* reply) {
  if (request->sha256_size() > kMaxHashes)
    return Invalid("at most " + std::to_string(kMaxHashes) + " hashes per call, got " +
                   std::to_string(request->sha256_size()));
  for (const std::string& hash : request->sha256()) {
    if (!IsSha256(hash)) {
      const std::string shown = hash.substr(0, 80);
      return Invalid("'" + shown + "' is not a SHA-256 (64 lowercase hex digits)");
    }
    const std::string user = CallerOf(*context).user;
    if (store_.Owns(hash, user)) store_.Touch(hash, user);  // about to be used
    else reply->add_sha256(hash);
  }
  return grpc::Status::OK;
}

grpc::Status AssetServiceImpl::Upload(grpc::ServerContext* context, grpc::ServerReader<v1::AssetChunk>* reader,
                                      v1::UploadAssetReply* reply) {
  v1::AssetChunk chunk;
  if (!reader->Read(&chunk)) return Invalid("an upload starts with a message naming the asset's sha256 and size");
  try {
    const auto room = store_.Reserve(chunk.sha256(), CallerOf(*context).user, chunk.size());
    AssetUpload upload(store_, chunk.sha256(), chunk.size());
    reply->set_sha256(chunk.sha256());
    do {
      if (chunk.data().size() > kMaxChunk)
        return Invalid("a chunk of " + std::to_string(chunk.data().size()) + " bytes; at most " +
                       std::to_string(kMaxChunk) + " (4 MiB) per message");
      if (!chunk.sha256().empty() && chunk.sha256() != reply->sha256())
        return Invalid("one upload carries one asset; a later chunk names " + chunk.sha256().substr(0, 80));
      upload.Append(chunk.data());
    } while (reader->Read(&chunk));
    // A client that gave up mid-stream ends the stream too: keep nothing.
    if (context->IsCancelled()) return grpc::Status::CANCELLED;
    reply->set_stored(upload.Commit());
    // The caller sent every byte of it: it is theirs too from now on.
    store_.AddOwner(reply->sha256(), CallerOf(*context).user);
    return grpc::Status::OK;
  } catch (const LimitReached& e) {
    return {grpc::StatusCode::RESOURCE_EXHAUSTED, e.what()};
  } catch (const Error& e) {
    return Invalid(e.what());
  } catch (const std::exception& e) {
    return {grpc::StatusCode::INTERNAL, e.what()};
  }
}

}  // namespace yarf
