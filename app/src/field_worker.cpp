#include "field_worker.h"

#include <chrono>
#include <cstdio>

#include "render/scene.h"

namespace at::app {

std::string FieldRequest::key() const {
  char buf[256];
  std::snprintf(buf, sizeof buf, "%u/ds%d/%s/%s/%g..%g/b%g/p%d%s/%s", unsigned(label), params.downsample,
                toString(params.rule), toString(params.weight), double(params.huMin), double(params.huMax),
                double(params.baseCost), params.passes, params.converge ? "c" : "", toString(params.backend));
  return buf;
}

FieldWorker::FieldWorker(const Dataset& dataset, std::size_t capacity)
    : dataset_(dataset), capacity_(capacity < 1 ? 1 : capacity), thread_([this] { run(); }) {}

FieldWorker::~FieldWorker() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
    queued_.reset();
    cancelRunning_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void FieldWorker::request(const FieldRequest& request) {
  const std::string key = request.key();
  {
    std::lock_guard lock(mutex_);
    for (const auto& entry : lru_)
      if (entry.first == key) return;
    if (runningKey_ && *runningKey_ == key) {
      queued_.reset();  // the running one is what the user wants now
      return;
    }
    if (runningKey_) cancelRunning_ = true;
    queued_ = request;
  }
  wake_.notify_all();
}

void FieldWorker::cancelAll() {
  std::lock_guard lock(mutex_);
  queued_.reset();
  if (runningKey_) cancelRunning_ = true;
}

std::shared_ptr<const DistanceField> FieldWorker::cached(const FieldRequest& request) {
  const std::string key = request.key();
  std::lock_guard lock(mutex_);
  for (auto it = lru_.begin(); it != lru_.end(); ++it)
    if (it->first == key) {
      lru_.splice(lru_.begin(), lru_, it);
      return lru_.front().second;
    }
  return nullptr;
}

std::vector<FinishedField> FieldWorker::takeFinished() {
  std::lock_guard lock(mutex_);
  return std::exchange(finished_, {});
}

bool FieldWorker::busy() const {
  std::lock_guard lock(mutex_);
  return runningKey_.has_value() || queued_.has_value();
}

std::optional<FieldWorker::Running> FieldWorker::running() const {
  std::lock_guard lock(mutex_);
  if (!runningRequest_) return std::nullopt;
  Running r;
  r.request = *runningRequest_;
  r.passesDone = passesDone_.load();
  r.passesPlanned = passesPlanned_.load();
  if (r.passesPlanned == 0) r.passesPlanned = r.request.params.converge ? r.request.params.maxPasses : r.request.params.passes;
  r.elapsedMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - runningSince_).count();
  return r;
}

void FieldWorker::insert(const std::string& key, std::shared_ptr<const DistanceField> field) {
  lru_.emplace_front(key, std::move(field));
  while (lru_.size() > capacity_) lru_.pop_back();
}

void FieldWorker::run() {
  for (;;) {
    FieldRequest job;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] { return stop_ || queued_.has_value(); });
      if (stop_) return;
      job = *queued_;
      queued_.reset();
      runningKey_ = job.key();
      runningRequest_ = job;
      runningSince_ = std::chrono::steady_clock::now();
      passesDone_ = 0;
      passesPlanned_ = 0;
      cancelRunning_ = false;
    }
    FinishedField done;
    done.request = job;
    const Structure* structure = dataset_.findStructureByLabel(job.label);
    if (!structure) {
      done.message = "no structure with label " + std::to_string(job.label);
    } else {
      const Mask seeds = render::structureMask(dataset_.labels, job.label);
      WdtControl control;
      control.cancel = &cancelRunning_;
      control.progress = [this](int done, int planned) {
        passesDone_ = done;
        passesPlanned_ = planned;
      };
      auto result = computeWdt(dataset_.volume, seeds, job.params, control);
      if (!result) {
        done.message = structure->id + ": " + result.error().message;
      } else if (result->stats.cancelled) {
        cancelled_.fetch_add(1);
        std::lock_guard lock(mutex_);
        runningKey_.reset();
        runningRequest_.reset();
        continue;  // stale: a newer request replaced it
      } else {
        done.field = std::make_shared<const DistanceField>(std::move(result->field));
        done.ms = result->stats.msTotal;
        done.device = result->stats.device;
        done.message = result->stats.warning;
      }
    }
    std::lock_guard lock(mutex_);
    if (done.field) insert(*runningKey_, done.field);
    runningKey_.reset();
    runningRequest_.reset();
    finished_.push_back(std::move(done));
  }
}

}  // namespace at::app
