#include "service/job_watches.h"

#include <vector>

namespace yarf {
namespace {

// How often the sender looks for jobs that changed: the lag a Watch may add.
constexpr std::chrono::milliseconds kPollInterval(50);

// A Watch refused before it started.
class RefusedWatch final : public grpc::ServerWriteReactor<v1::JobStatus> {
 public:
  explicit RefusedWatch(const grpc::Status& status) { Finish(status); }
  void OnDone() override { delete this; }
};

}  // namespace

// One Watch stream: at most one write in flight; the next status goes out
// when the job's version moves past the one last sent. Every member is
// guarded by the table's mutex.
class JobWatches::Stream final : public grpc::ServerWriteReactor<v1::JobStatus> {
 public:
  Stream(JobWatches& table, std::shared_ptr<Job> job, std::string user)
      : table_(table), job_(std::move(job)), user_(std::move(user)) {}

  const std::string& user() const { return user_; }
  bool WantsSending() const { return !writing_ && !finished_ && job_->Version() != seen_; }

  // The job's current status; StartWrite last, since the reactor may end
  // (and be deleted) before it returns.
  void Send() {
    seen_ = job_->Version();
    status_ = job_->Status();
    writing_ = true;
    StartWrite(&status_);
  }

  void OnWriteDone(bool ok) override {
    std::lock_guard lock(table_.mutex_);
    writing_ = false;
    if (!ok) return FinishOnce(grpc::Status::OK);  // the client left
    if (Ended(status_.state())) return FinishOnce(grpc::Status::OK);
    if (WantsSending()) Send();  // it changed again while the write went out
  }

  void OnCancel() override {
    std::lock_guard lock(table_.mutex_);
    FinishOnce(grpc::Status::CANCELLED);
  }

  void OnDone() override {
    table_.Remove(this);
    delete this;  // gRPC's reactors own themselves once started
  }

 private:
  void FinishOnce(const grpc::Status& status) {
    if (std::exchange(finished_, true)) return;
    Finish(status);
  }

  JobWatches& table_;
  const std::shared_ptr<Job> job_;
  const std::string user_;
  v1::JobStatus status_;
  uint64_t seen_ = 0;
  bool writing_ = false, finished_ = false;
};

JobWatches::JobWatches(uint32_t max_per_user)
    : max_per_user_(max_per_user), sender_([this] { SendChanges(); }) {}

JobWatches::~JobWatches() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
}

grpc::ServerWriteReactor<v1::JobStatus>* JobWatches::Refuse(const grpc::Status& status) {
  return new RefusedWatch(status);
}

grpc::ServerWriteReactor<v1::JobStatus>* JobWatches::Watch(std::shared_ptr<Job> job, const std::string& user) {
  std::lock_guard lock(mutex_);
  uint32_t& open = per_user_[user];
  if (open >= max_per_user_)
    return Refuse({grpc::StatusCode::RESOURCE_EXHAUSTED,
                             user + " has " + std::to_string(open) + " Watch streams open, the most one user may (" +
                                 "yarfd --max-watches-per-user); close some first"});
  ++open;
  auto* stream = new Stream(*this, std::move(job), user);
  streams_.insert(stream);
  stream->Send();  // the status as it is now, at once
  return stream;
}

void JobWatches::Remove(Stream* stream) {
  std::lock_guard lock(mutex_);
  if (streams_.erase(stream) && --per_user_[stream->user()] == 0) per_user_.erase(stream->user());
}

void JobWatches::SendChanges() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    wake_.wait_for(lock, kPollInterval, [&] { return stopping_; });
    std::vector<Stream*> changed;
    for (Stream* stream : streams_)
      if (stream->WantsSending()) changed.push_back(stream);
    for (Stream* stream : changed) stream->Send();
  }
}

}  // namespace yarf
