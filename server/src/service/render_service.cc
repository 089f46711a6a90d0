#include "service/render_service.h"

#include <chrono>

#include "kernel/image_io.h"
#include "components/array_codec.h"
#include "yarf/error.h"

namespace yarf {
namespace {

grpc::Status NotFound(const std::string& id) {
  return {grpc::StatusCode::NOT_FOUND, "no job '" + id + "'"};
}

bool Ended(v1::JobState s) { return s == v1::SUCCEEDED || s == v1::FAILED || s == v1::CANCELLED; }

}  // namespace

grpc::Status RenderServiceImpl::Submit(grpc::ServerContext*, const v1::SubmitRequest* request,
                                       v1::SubmitReply* reply) {
  try {
    reply->set_job_id(jobs_.Submit(*request));
    return grpc::Status::OK;
  } catch (const Error& e) {
    return {grpc::StatusCode::INVALID_ARGUMENT, e.what()};
  }
}

grpc::Status RenderServiceImpl::Watch(grpc::ServerContext* context, const v1::WatchRequest* request,
                                      grpc::ServerWriter<v1::JobStatus>* writer) {
  auto job = jobs_.Find(request->job_id());
  if (!job) return NotFound(request->job_id());
  uint64_t seen = job->Version();
  for (;;) {
    const v1::JobStatus status = job->Status();
    if (!writer->Write(status)) return grpc::Status::OK;  // the client left
    if (Ended(status.state())) return grpc::Status::OK;
    // Short waits so a client that left is noticed promptly.
    while (job->Version() == seen) {
      if (context->IsCancelled()) return grpc::Status::CANCELLED;
      job->WaitForChange(seen, std::chrono::milliseconds(200));
    }
    seen = job->Version();
  }
}

grpc::Status RenderServiceImpl::GetResult(grpc::ServerContext*, const v1::GetResultRequest* request,
                                          v1::GetResultReply* reply) {
  auto job = jobs_.Find(request->job_id());
  if (!job) return NotFound(request->job_id());
  *reply->mutable_status() = job->Status();
  std::vector<float> pixels, variances;
  uint32_t width = 0, height = 0;
  if (!job->Snapshot(pixels, variances, width, height))
    return {grpc::StatusCode::FAILED_PRECONDITION,
            "job '" + request->job_id() + "' has no image" +
                (reply->status().error().empty() ? "" : ": " + reply->status().error())};
  try {
    switch (request->format()) {
      case v1::GetResultRequest::EXR:
        reply->set_image(EncodeImage(pixels, width, height, ImageFormat::kExr));
        break;
      case v1::GetResultRequest::PNG:
        reply->set_image(EncodeImage(pixels, width, height, ImageFormat::kPng));
        break;
      default:
        *reply->mutable_pixels() = FloatArray(pixels, {height, width, 3});
        *reply->mutable_variance() = FloatArray(variances, {height, width, 3});
    }
  } catch (const Error& e) {
    return {grpc::StatusCode::INTERNAL, e.what()};
  }
  return grpc::Status::OK;
}

grpc::Status RenderServiceImpl::Cancel(grpc::ServerContext*, const v1::CancelRequest* request,
                                       v1::CancelReply* reply) {
  auto job = jobs_.Find(request->job_id());
  if (!job) return NotFound(request->job_id());
  job->RequestCancel();
  *reply->mutable_status() = job->Status();
  return grpc::Status::OK;
}

grpc::Status RenderServiceImpl::List(grpc::ServerContext*, const v1::ListJobsRequest*,
                                     v1::ListJobsReply* reply) {
  for (const auto& job : jobs_.List()) *reply->add_jobs() = job->Status();
  return grpc::Status::OK;
}

}  // namespace yarf
