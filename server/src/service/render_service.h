// yarf.v1.RenderService over the job table. Callers see and act on the
// jobs access.h lets them: their own, or everyone's for the admin role.
#pragma once

#include <semaphore>

#include "service/job_watches.h"
#include "service/jobs.h"
#include "yarf/v1/render.grpc.pb.h"

namespace yarf {

// Watch is a callback method (job_watches.h): streams wait without a thread.
class RenderServiceImpl final : public v1::RenderService::WithCallbackMethod_Watch<v1::RenderService::Service> {
 public:
  RenderServiceImpl(JobManager& jobs, uint32_t max_watches_per_user) : jobs_(jobs), watches_(max_watches_per_user) {}

  grpc::Status Submit(grpc::ServerContext*, const v1::SubmitRequest*, v1::SubmitReply*) override;
  grpc::ServerWriteReactor<v1::JobStatus>* Watch(grpc::CallbackServerContext*, const v1::WatchRequest*) override;
  grpc::Status GetResult(grpc::ServerContext*, const v1::GetResultRequest*, v1::GetResultReply*) override;
  grpc::Status Cancel(grpc::ServerContext*, const v1::CancelRequest*, v1::CancelReply*) override;
  grpc::Status List(grpc::ServerContext*, const v1::ListJobsRequest*, v1::ListJobsReply*) override;
  grpc::Status SetPriority(grpc::ServerContext*, const v1::SetPriorityRequest*, v1::JobStatus*) override;
  grpc::Status GetJob(grpc::ServerContext*, const v1::GetJobRequest*, v1::JobDetails*) override;

 private:
  // The job, if the caller may act on it; else why not.
  grpc::Status Reach(const grpc::ServerContextBase& context, const std::string& id,
                     std::shared_ptr<Job>& job) const;

  JobManager& jobs_;
  JobWatches watches_;
  // GetResult copies a film (and encodes it) at most this many at a time:
  // each copy of a large film takes gigabytes, and clients may ask at once.
  static constexpr int kImageCopies = 2;
  std::counting_semaphore<kImageCopies> image_copies_{kImageCopies};
};

}  // namespace yarf
