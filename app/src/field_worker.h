// Distance fields for the desktop view, computed off the UI thread (issue 7, "hover to highlight").
//
// One worker thread; requests are latest-wins: a new request replaces the pending one, and the
// running computation is cancelled through WdtControl::cancel unless it is for the same key. The
// UI thread never waits: it asks `cached` for what exists and `takeFinished` for what arrived.
// Finished fields go into a small LRU cache keyed by structure label, downsample factor and the
// WDT parameters that shape the field.
//
// With a CUDA device (backend auto or cuda), the worker uploads the dataset's HU and labels to the
// GPU once and computes each field there (cuda::DeviceVolume): nothing is uploaded per field, and
// the field stays on the device as well, so the view can take it through CUDA–GL interop
// (`cachedOnDevice`) instead of uploading the host copy. The host copy is still made (off the UI
// thread) for picking. Any CUDA failure under `auto` falls back to computeWdt's CPU path with a
// one-line message.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <list>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "volume/structure.h"
#include "wdt/wdt.h"

namespace at::cuda {
class DeviceField;
}

namespace at::app {

struct FieldRequest {
  std::uint16_t label = 0;
  WdtParams params;          // params.downsample picks the resolution
  std::string key() const;   // label, downsample and every parameter that changes the field
};

struct FinishedField {
  FieldRequest request;
  std::shared_ptr<const DistanceField> field;  // null when it failed, or for a GPU field (below)
  // A field computed on the GPU: its device copy. Its host copy (for picking) follows in the
  // cache (`cached`) a little later; `field` stays null here.
  std::shared_ptr<const cuda::DeviceField> deviceField;
  double ms = 0;
  std::string device;
  std::string message;  // error, or the backend's warning (e.g. why auto fell back to the CPU)
};

class FieldWorker {
 public:
  // `dataset` must outlive the worker. `capacity`: fields kept in the LRU cache (≥ 1).
  FieldWorker(const Dataset& dataset, std::size_t capacity);
  ~FieldWorker();
  FieldWorker(const FieldWorker&) = delete;
  FieldWorker& operator=(const FieldWorker&) = delete;

  // Queues `request` unless it is cached or already running; replaces any queued request and
  // cancels a running one for another key.
  void request(const FieldRequest& request);
  // Drops the queued request and cancels the running one (e.g. the user left the structure).
  void cancelAll();
  // The cached field for `request`, marking it most recently used. `host` is null while a GPU
  // field's host copy is still being made; `device` is set only for fields computed on the GPU.
  struct Cached {
    std::shared_ptr<const DistanceField> host;
    std::shared_ptr<const cuda::DeviceField> device;
    bool ready() const { return host || device; }
  };
  Cached cached(const FieldRequest& request);
  // Fields (and failures) finished since the last call, oldest first.
  std::vector<FinishedField> takeFinished();
  bool busy() const;
  // The computation running now, for a progress bar: its request, passes done of passes planned
  // (the WDT reports after each pass) and how long it has run. nullopt when idle.
  struct Running {
    FieldRequest request;
    int passesDone = 0, passesPlanned = 0;
    double elapsedMs = 0;
  };
  std::optional<Running> running() const;
  // Computations cancelled because a newer request arrived (for the log and tests).
  int cancelledCount() const { return cancelled_.load(); }

 private:
  void run();
  struct Entry {
    std::string key;
    std::shared_ptr<const DistanceField> field;
    std::shared_ptr<const cuda::DeviceField> deviceField;
  };
  void insert(Entry entry);
  // The field on the GPU (device-resident volume). Published: the entry (device field first, its
  // host copy attached when made) and the finished record are in place. NotUsed: no device or
  // backend cpu — use computeWdt. GaveUp: a CUDA failure under `auto`, now or before — compute
  // on the CPU. Worker thread only.
  struct DeviceOutcome {
    enum Kind { NotUsed, GaveUp, Published, Cancelled, Failed } kind = NotUsed;
    FinishedField failure;  // Failed (backend cuda): what to report
  };
  DeviceOutcome computeOnDevice(const FieldRequest& job, WdtControl& control);

  const Dataset& dataset_;
  const std::size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::optional<FieldRequest> queued_;
  std::optional<std::string> runningKey_;
  std::optional<FieldRequest> runningRequest_;
  std::chrono::steady_clock::time_point runningSince_;
  std::atomic<int> passesDone_{0}, passesPlanned_{0};
  std::atomic<bool> cancelRunning_{false};
  std::atomic<int> cancelled_{0};
  bool stop_ = false;
  std::list<Entry> lru_;  // front = newest
  struct DeviceState;
  std::unique_ptr<DeviceState> device_;  // worker thread only
  std::string deviceWarning_;            // why the GPU path was given up, for the next result
  std::vector<FinishedField> finished_;
  std::thread thread_;
};

}  // namespace at::app
