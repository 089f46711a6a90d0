#include "service/render_service.h"

#include <chrono>
#include <vector>

#include "components/array_codec.h"
#include "kernel/image_io.h"
#include "service/access.h"
#include "yarf/error.h"

namespace yarf {
namespace {

// Whether a message names a component process anywhere (a Material's or
// a ComponentSpec's `address`): yarfd would dial that address and hand
// the process the job's scene.
bool NamesAddress(const google::protobuf::Message& message) {
  const google::protobuf::Reflection& reflection = *message.GetReflection();
  std::vector<const google::protobuf::FieldDescriptor*> fields;
  reflection.ListFields(message, &fields);
  for (const google::protobuf::FieldDescriptor* field : fields) {
    if (field->cpp_type() == google::protobuf::FieldDescriptor::CPPTYPE_STRING && field->name() == "address" &&
        !field->is_repeated() && !reflection.GetString(message, field).empty())
      return true;
    if (field->cpp_type() != google::protobuf::FieldDescriptor::CPPTYPE_MESSAGE) continue;
    if (field->is_repeated()) {
      for (int i = 0; i < reflection.FieldSize(message, field); ++i)
        if (NamesAddress(reflection.GetRepeatedMessage(message, field, i))) return true;
    } else if (NamesAddress(reflection.GetMessage(message, field))) {
      return true;
    }
  }
  return false;
}

}  // namespace

grpc::Status RenderServiceImpl::Reach(const grpc::ServerContext& context, const std::string& id,
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
  // Other users' processes are reached through classes an admin registered.
  if (caller.role != Role::kAdmin && NamesAddress(*request))
    return {grpc::StatusCode::PERMISSION_DENIED,
            "naming a component process by address needs the admin role; use a class an admin registered"};
  try {
    reply->set_job_id(jobs_.Submit(*request, caller.user));
    return grpc::Status::OK;
  } catch (const Error& e) {
    return {grpc::StatusCode::INVALID_ARGUMENT, e.what()};
  } catch (const StorageError& e) {
    return {grpc::StatusCode::INTERNAL, std::string("the job could not be stored: ") + e.what()};
  }
}

grpc::Status RenderServiceImpl::Watch(grpc::ServerContext* context, const v1::WatchRequest* request,
                                      grpc::ServerWriter<v1::JobStatus>* writer) {
  std::shared_ptr<Job> job;
  if (grpc::Status reached = Reach(*context, request->job_id(), job); !reached.ok()) return reached;
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

grpc::Status RenderServiceImpl::GetResult(grpc::ServerContext* context, const v1::GetResultRequest* request,
                                          v1::GetResultReply* reply) {
  std::shared_ptr<Job> job;
  if (grpc::Status reached = Reach(*context, request->job_id(), job); !reached.ok()) return reached;
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
  for (const auto& job : jobs_.List())
    if (MayActOn(caller, job->owner())) *reply->add_jobs() = job->Status();
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
