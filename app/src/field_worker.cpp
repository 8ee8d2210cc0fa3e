#include "field_worker.h"

#include <chrono>
#include <cstdio>

#include "render/scene.h"
#include "volume/mask.h"

#if defined(AT_HAVE_CUDA)
#include "cuda/wdt_cuda.h"
#include "wdt/huge_pages.h"
#endif

namespace at::app {

#if defined(AT_HAVE_CUDA)
struct FieldWorker::DeviceState {
  std::optional<cuda::DeviceVolume> volume;
  bool unusable = false;  // the upload or a run failed: computeWdt from now on
};
#else
struct FieldWorker::DeviceState {};
#endif

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
      if (entry.key == key) return;
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

FieldWorker::Cached FieldWorker::cached(const FieldRequest& request) {
  const std::string key = request.key();
  std::lock_guard lock(mutex_);
  for (auto it = lru_.begin(); it != lru_.end(); ++it)
    if (it->key == key) {
      lru_.splice(lru_.begin(), lru_, it);
      return {lru_.front().field, lru_.front().deviceField};
    }
  return {};
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

void FieldWorker::insert(Entry entry) {
  lru_.push_front(std::move(entry));
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
      WdtControl control;
      control.cancel = &cancelRunning_;
      control.progress = [this](int done, int planned) {
        passesDone_ = done;
        passesPlanned_ = planned;
      };
      const DeviceOutcome onDevice = computeOnDevice(job, control);
      if (onDevice.kind != DeviceOutcome::NotUsed && onDevice.kind != DeviceOutcome::GaveUp) {
        if (onDevice.kind == DeviceOutcome::Cancelled) cancelled_.fetch_add(1);
        std::lock_guard lock(mutex_);
        if (onDevice.kind == DeviceOutcome::Failed) finished_.push_back(onDevice.failure);
        runningKey_.reset();
        runningRequest_.reset();
        continue;
      }
      WdtParams params = job.params;
      if (onDevice.kind == DeviceOutcome::GaveUp) params.backend = WdtBackend::Cpu;  // as the warning says
      const Mask seeds = structureMask(dataset_.labels, job.label);
      auto result = computeWdt(dataset_.volume, seeds, params, control);
      if (result && !deviceWarning_.empty()) result->stats.warning = std::exchange(deviceWarning_, "");
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
    if (done.field) insert({*runningKey_, done.field, nullptr});
    runningKey_.reset();
    runningRequest_.reset();
    finished_.push_back(std::move(done));
  }
}

FieldWorker::DeviceOutcome FieldWorker::computeOnDevice(const FieldRequest& job, WdtControl& control) {
  DeviceOutcome outcome;
#if defined(AT_HAVE_CUDA)
  if (job.params.backend == WdtBackend::Cpu || !cuda::queryDevice().available) return outcome;
  if (!device_) device_ = std::make_unique<DeviceState>();
  DeviceState& d = *device_;
  if (d.unusable) {
    outcome.kind = DeviceOutcome::GaveUp;
    return outcome;
  }
  auto giveUp = [&](const std::string& why) {
    d.unusable = true;
    d.volume.reset();
    if (job.params.backend == WdtBackend::Cuda) {
      outcome.kind = DeviceOutcome::Failed;
      outcome.failure.request = job;
      outcome.failure.message = why;
    } else {
      outcome.kind = DeviceOutcome::GaveUp;
      deviceWarning_ = "CUDA backend failed, computed on the CPU instead: " + why;
    }
    return outcome;
  };
  const auto t0 = std::chrono::steady_clock::now();
  if (!d.volume) {
    auto uploaded = cuda::uploadVolume(dataset_.volume, dataset_.labels);
    if (!uploaded) return giveUp(uploaded.error().message);
    d.volume = std::move(*uploaded);
  }
  WdtStats stats;
  auto field = cuda::runCudaBackendOnDevice(*d.volume, job.label, job.params, control, &stats);
  if (!field) return giveUp(field.error().message);
  if (stats.cancelled) {
    outcome.kind = DeviceOutcome::Cancelled;
    return outcome;
  }
  // Published at once: the view shows the device field through interop while the host copy,
  // which only picking reads, is still being made.
  const std::string key = job.key();
  auto device = std::make_shared<const cuda::DeviceField>(std::move(*field));
  FinishedField done;
  done.request = job;
  done.deviceField = device;
  done.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  done.device = stats.device;
  {
    std::lock_guard lock(mutex_);
    insert({key, nullptr, device});
    finished_.push_back(std::move(done));
  }
  auto host = std::make_shared<DistanceField>();
  host->downsample = device->downsample();
  // Fresh memory on huge pages: 4 KiB page faults would cost more than the copy (~40 ms at 256³).
  wdt::resizeOnHugePages(host->distances.voxels, device->grid().dims.count());
  const Status copied = cuda::copyToHost(*device, host->distances);
  std::lock_guard lock(mutex_);
  for (auto it = lru_.begin(); it != lru_.end(); ++it) {
    if (it->key != key || it->deviceField != device) continue;
    if (copied) it->field = std::move(host);
    else lru_.erase(it);  // without a host copy the entry is dropped and recomputed on the CPU
    break;
  }
  if (!copied) {
    d.unusable = true;
    deviceWarning_ = "CUDA backend failed, computed on the CPU instead: " + copied.error().message;
  }
  outcome.kind = DeviceOutcome::Published;
  return outcome;
#else
  (void)job;
  (void)control;
  return outcome;
#endif
}

}  // namespace at::app
