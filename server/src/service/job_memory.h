// What a job will take in memory, estimated before it is accepted, so that
// a request for a film or a mesh larger than the server can hold is
// refused at Submit (yarfd --max-job-memory) instead of failing, or taking
// the server down, when it runs.
#pragma once

#include <cstdint>
#include <filesystem>

#include "service/asset_store.h"
#include "yarf/v1/render.pb.h"

namespace yarf {

// Bytes the film (its accumulators, splats, snapshots and checkpoint
// buffers), the meshes (parsed, and Embree's BVH over them), the
// placements of `request` and the images and volume grids its components
// decode (from the files' headers) will need; asset files are sized from
// `assets`, others from `asset_root`, where they are. Components' own
// memory (a photon map) is theirs to bound through their parameters. Mesh
// files are read and counted (gzip ones inflated) up to `limit` bytes: a
// larger one is not read, since the job cannot be accepted.
uint64_t EstimateJobBytes(const v1::SubmitRequest& request, const AssetStore* assets,
                          const std::filesystem::path& asset_root, uint64_t limit);

// A default for --max-job-memory: half the machine's memory.
uint64_t DefaultMaxJobBytes();

}  // namespace yarf
