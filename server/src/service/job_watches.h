// RenderService.Watch without a thread per stream: each Watch is a gRPC
// callback reactor, and one thread of this table sends every stream its
// job's next status when the job changes. A thousand idle Watches cost a
// thousand small objects, not a thousand blocked threads.
#pragma once

#include <grpcpp/support/server_callback.h>

#include <chrono>
#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>

#include "service/job.h"
#include "yarf/v1/render.pb.h"

namespace yarf {

class JobWatches {
 public:
  // At most `max_per_user` open Watch streams per user.
  explicit JobWatches(uint32_t max_per_user);
  // Ends every stream still open (CANCELLED), then the sending thread.
  ~JobWatches();
  JobWatches(const JobWatches&) = delete;
  JobWatches& operator=(const JobWatches&) = delete;

  // A reactor streaming `job`'s status to `user` until the job ends or the
  // client leaves; RESOURCE_EXHAUSTED when the user has too many open.
  // gRPC owns the reactor until its OnDone.
  grpc::ServerWriteReactor<v1::JobStatus>* Watch(std::shared_ptr<Job> job, const std::string& user);
  // A reactor that ends the stream at once with `status`.
  static grpc::ServerWriteReactor<v1::JobStatus>* Refuse(const grpc::Status& status);

 private:
  class Stream;
  friend class Stream;

  // Sends the streams whose job changed; runs on `sender_`.
  void SendChanges();
  void Remove(Stream* stream);

  const uint32_t max_per_user_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::set<Stream*> streams_;
  std::map<std::string, uint32_t> per_user_;
  std::jthread sender_;
};

}  // namespace yarf
