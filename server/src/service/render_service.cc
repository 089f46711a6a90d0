#include "service/render_service.h"

#include <chrono>
#include <string>
#include <utility>
#include <vector>

#include "components/array_codec.h"
#include "kernel/image_io.h"
#include "service/access.h"
#include "service/request_checks.h"
#include "service/server_options.h"
#include "yarf/error.h"

namespace yarf {
namespace {

// Whether a RAW reply of a width x height image stays within what a reply
// may carry; else RESOURCE_EXHAUSTED pointing to the smaller formats.
grpc::Status RawFits(const std::string& job_id, uint32_t width, uint32_t height, size_t aovs = 0) {
  // Pixels, variances and aovs, 3 floats each per pixel, and room for the status.
  const uint64_t bytes = uint64_t(width) * height * 3 * sizeof(float) * (2 + aovs) + (64 << 10);
  if (bytes <= uint64_t(kMaxMessageBytes)) return grpc::Status::OK;
  return {grpc::StatusCode::RESOURCE_EXHAUSTED,
          "the RAW result of job '" + job_id + "' (" + std::to_string(width) + "x" + std::to_string(height) +
              " pixels, their variances and aovs) takes " + std::to_string(bytes) + " bytes, more than the " +
              std::to_string(kMaxMessageBytes) +
              " (256 MiB) a reply may carry; ask for EXR or PNG (about 6 or 3 bytes a pixel at most)"};
}

// One of a semaphore's places, held for a scope.
template <typename Semaphore>
class HeldPlace {
 public:
  explicit HeldPlace(Semaphore& places) : places_(places) { places_.acquire(); }
  ~HeldPlace() { places_.release(); }
  HeldPlace(const HeldPlace&) = delete;
  HeldPlace& operator=(const HeldPlace&) = delete;

 private:
  Semaphore& places_;
};

// How much of each job's error List shows.
constexpr size_t kListedErrorBytes = 1 << 10;

}  // namespace

grpc::Status RenderServiceImpl::Reach(const grpc::ServerContextBase& context, const std::string& id,
                                      std::shared_ptr<Job>& job) const {
  job = jobs_.Find(id);
  if (!job) return {grpc::StatusCode::NOT_FOUND, "no job '" + id + "'"};
  const Caller caller = CallerOf(context);
  if (!MayActOn(caller, job->owner()))
    return {grpc::StatusCode::PERMISSION_DENIED, "job '" + id + "' is not " + caller.user + "'s"};
  return grpc::Status::OK;
}

grpc::Status RenderServiceImpl::Submit(grpc::ServerContext* context, const v1::SubmitRequest* request,
                                       v1::SubmitReply* reply) {
  const Caller caller = CallerOf(*context);
  if (grpc::Status allowed = MayNameAddresses(caller, *request); !allowed.ok()) return allowed;
  try {
    std::vector<std::string> warnings;
    reply->set_job_id(jobs_.Submit(*request, caller.user, &warnings));
    for (std::string& warning : warnings) reply->add_warnings(std::move(warning));
    return grpc::Status::OK;
  } catch (const LimitReached& e) {
    return {grpc::StatusCode::RESOURCE_EXHAUSTED, e.what()};
  } catch (const Error& e) {
    // Errors may quote the request: cut and mended as every error shown.
    return {grpc::StatusCode::INVALID_ARGUMENT, SafeText(e.what(), RequestLimits::kMaxErrorBytes)};
  } catch (const StorageError& e) {
    return {grpc::StatusCode::INTERNAL, std::string("the job could not be stored: ") + e.what()};
  }
}

grpc::ServerWriteReactor<v1::JobStatus>* RenderServiceImpl::Watch(grpc::CallbackServerContext* context,
                                                                  const v1::WatchRequest* request) {
  std::shared_ptr<Job> job;
  if (grpc::Status reached = Reach(*context, request->job_id(), job); !reached.ok())
    return JobWatches::Refuse(reached);
  return watches_.Watch(std::move(job), CallerOf(*context).user);
}

grpc::Status RenderServiceImpl::GetResult(grpc::ServerContext* context, const v1::GetResultRequest* request,
                                          v1::GetResultReply* reply) {
  std::shared_ptr<Job> job;
  if (grpc::Status reached = Reach(*context, request->job_id(), job); !reached.ok()) return reached;
  *reply->mutable_status() = job->Status();
  const bool raw = request->format() != v1::GetResultRequest::EXR && request->format() != v1::GetResultRequest::PNG;
  uint32_t width = 0, height = 0;
  // Before any copy of the film: a RAW reply too large to send is refused
  // at once, not after several copies of a film that may take gigabytes.
  if (raw && job->ImageSize(width, height))
    if (grpc::Status fits = RawFits(request->job_id(), width, height); !fits.ok()) return fits;
  const HeldPlace copying(image_copies_);
  std::vector<float> pixels, variances;
  if (!job->Snapshot(pixels, variances, width, height))
    return {grpc::StatusCode::FAILED_PRECONDITION,
            "job '" + request->job_id() + "' has no image" +
                (reply->status().error().empty() ? "" : ": " + reply->status().error())};
  // Again for a film that appeared in between.
  if (raw)
    if (grpc::Status fits = RawFits(request->job_id(), width, height); !fits.ok()) return fits;
  const std::vector<ImageLayer> aovs = job->AovSnapshot();
  if (raw)
    if (grpc::Status fits = RawFits(request->job_id(), width, height, aovs.size()); !fits.ok()) return fits;
  try {
    switch (request->format()) {
      case v1::GetResultRequest::EXR:
        reply->set_image(EncodeImage(pixels, width, height, ImageFormat::kExr, aovs));
        break;
      case v1::GetResultRequest::PNG:
        reply->set_image(EncodeImage(pixels, width, height, ImageFormat::kPng));
        break;
      default:
        *reply->mutable_pixels() = FloatArray(pixels, {height, width, 3});
        *reply->mutable_variance() = FloatArray(variances, {height, width, 3});
        for (const ImageLayer& aov : aovs) {
          v1::ImageLayer* layer = reply->add_aovs();
          layer->set_name(aov.name);
          *layer->mutable_pixels() = FloatArray(aov.rgb, {height, width, 3});
        }
    }
  } catch (const Error& e) {
    return {grpc::StatusCode::INTERNAL, e.what()};
  }
  // An encoded image's size is known only now; said plainly rather than
  // left to the transport's limit.
  if (reply->image().size() + (64 << 10) > size_t(kMaxMessageBytes))
    return {grpc::StatusCode::RESOURCE_EXHAUSTED,
            "the " + std::string(request->format() == v1::GetResultRequest::EXR ? "EXR" : "PNG") +
                " image of job '" + request->job_id() + "' takes " + std::to_string(reply->image().size()) +
                " bytes, more than the " + std::to_string(kMaxMessageBytes) + " (256 MiB) a reply may carry"};
  return grpc::Status::OK;
}

grpc::Status RenderServiceImpl::GetJob(grpc::ServerContext* context, const v1::GetJobRequest* request,
                                       v1::JobDetails* reply) {
  std::shared_ptr<Job> job;
  if (grpc::Status reached = Reach(*context, request->job_id(), job); !reached.ok()) return reached;
  *reply = job->Details();
  return grpc::Status::OK;
}

grpc::Status RenderServiceImpl::Cancel(grpc::ServerContext* context, const v1::CancelRequest* request,
                                       v1::CancelReply* reply) {
  std::shared_ptr<Job> job;
  if (grpc::Status reached = Reach(*context, request->job_id(), job); !reached.ok()) return reached;
  try {
    jobs_.Cancel(*job);
  } catch (const StorageError& e) {
    return {grpc::StatusCode::INTERNAL, e.what()};
  }
  *reply->mutable_status() = job->Status();
  return grpc::Status::OK;
}

grpc::Status RenderServiceImpl::List(grpc::ServerContext* context, const v1::ListJobsRequest*,
                                     v1::ListJobsReply* reply) {
  const Caller caller = CallerOf(*context);
  for (const auto& job : jobs_.List()) {
    if (!MayActOn(caller, job->owner())) continue;
    v1::JobStatus* status = reply->add_jobs();
    *status = job->Status();
    // A listing of every job stays within any client's 4 MiB: the whole
    // error is the job's own status (Watch, GetResult).
    status->set_error(SafeText(status->error(), kListedErrorBytes));
  }
  return grpc::Status::OK;
}

grpc::Status RenderServiceImpl::SetPriority(grpc::ServerContext* context, const v1::SetPriorityRequest* request,
                                            v1::JobStatus* reply) {
  std::shared_ptr<Job> job;
  if (grpc::Status reached = Reach(*context, request->job_id(), job); !reached.ok()) return reached;
  try {
    if (!jobs_.SetPriority(*job, request->priority()))
      return {grpc::StatusCode::FAILED_PRECONDITION, "job '" + request->job_id() + "' has ended"};
  } catch (const Error& e) {
    return {grpc::StatusCode::INVALID_ARGUMENT, e.what()};
  } catch (const StorageError& e) {
    return {grpc::StatusCode::INTERNAL, e.what()};
  }
  *reply = job->Status();
  return grpc::Status::OK;
}

}  // namespace yarf
