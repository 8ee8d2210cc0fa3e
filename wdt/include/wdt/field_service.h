// Distance fields for an interactive view, computed off the caller's thread (the desktop's hover
// highlight and its locate click; ARCHITECTURE.md §2).
//
// One worker thread; requests are latest-wins: a new request replaces the pending one, and the
// running computation is cancelled through WdtControl::cancel unless it is for the same key. The
// caller asks `cached` for what exists and `takeFinished` for what arrived; it waits only where it
// asks to, for a bounded time (`waitFor`).
// Prefetches (`prefetch`: fields the caller expects to need soon, e.g. a lesson's next steps) run
// only while no request is queued or running, in the order given; a request cancels a running
// prefetch for another key (the prefetch is tried again afterwards), and a request for the key a
// prefetch is computing takes that computation over.
// Finished fields go into a small LRU cache keyed by structure label, downsample factor and the
// WDT parameters that shape the field.
//
// With a CUDA device (backend auto or cuda), the service uploads the HU volume and labels to the
// GPU once and computes each field there: nothing is uploaded per field, and the field stays on
// the device as well, so a renderer can take it through CUDA–GL interop (`Cached::device`) instead
// of uploading the host copy. The host copy is still made (off the caller's thread) for picking.
// The backend is chosen by the same rule as computeWdt (one auto→CPU fallback, cpu_fallback.h):
// after a CUDA failure under `auto` the service stays on the CPU and says why once.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <cstdint>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "volume/grid.h"
#include "wdt/wdt.h"

namespace at::cuda {
class DeviceField;  // opaque here: only a renderer with CUDA–GL interop looks inside
}

namespace at::wdt {

struct FieldRequest {
  std::uint16_t label = 0;   // the structure: its voxels are the seeds
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
  bool prefetched = false;  // computed for `prefetch`, not asked for by `request`
};

class FieldService {
 public:
  // `volume` and `labels` (on the volume's grid) must outlive the service. `capacity`: fields kept
  // in the LRU cache (≥ 1).
  FieldService(const Volume& volume, const LabelMap& labels, std::size_t capacity);
  ~FieldService();
  FieldService(const FieldService&) = delete;
  FieldService& operator=(const FieldService&) = delete;

  // Queues `request` unless it is cached or already running; replaces any queued request and
  // cancels a running one for another key.
  void request(const FieldRequest& request);
  // Drops the queued request and cancels the running one (e.g. the user left the structure).
  // Prefetches stay listed.
  void cancelAll();
  // Replaces the list of fields to compute while the service is otherwise idle (cached ones are
  // skipped); an empty list drops it and cancels a running prefetch. Fields on the list stay in
  // the cache while it lists them: the cache evicts the least recently used field not on it
  // (a caller keeps the list well below the capacity, FieldView::prefetch).
  void prefetch(const std::vector<FieldRequest>& requests);
  // While held, no listed prefetch starts (one already running goes on); requests are not held.
  // For a caller whose own work competes for the same cores (a software renderer converging).
  void holdPrefetches(bool hold);
  // A prefetch is listed or running.
  bool prefetching() const;
  // The field of `request` is being computed now (asked for or prefetched).
  bool computing(const FieldRequest& request) const;
  // The labels the service reads are edited (the segment editor): the running computation is
  // cancelled and waited for (at most one WDT pass), then `write` changes the labels while no
  // computation reads them; cached fields of the `changed` labels are dropped, and a device copy
  // of the labels is made again before the next field. A queued request stays queued.
  void updateLabels(const std::function<void()>& write, const std::vector<std::uint16_t>& changed);
  // The cached field for `request`, marking it most recently used. `host` is null while a GPU
  // field's host copy is still being made; `device` is set only for fields computed on the GPU.
  struct Cached {
    std::shared_ptr<const DistanceField> host;
    std::shared_ptr<const cuda::DeviceField> device;
    bool ready() const { return host || device; }
  };
  Cached cached(const FieldRequest& request);
  // Waits at most `limit` while the field of `request` is queued or running and not yet cached,
  // then returns what `cached` returns. For a caller that can afford a short wait: a frame that
  // would otherwise show the new field one frame later (a GPU field takes a few ms).
  Cached waitFor(const FieldRequest& request, std::chrono::milliseconds limit);
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
  struct Entry {
    std::uint16_t label = 0;
    std::string key;
    std::shared_ptr<const DistanceField> field;
    std::shared_ptr<const cuda::DeviceField> deviceField;
  };
  // What one computation came to: cancelled (stale), already published (a GPU field: its entry
  // and finished record are in place), or a finished record to publish.
  struct Outcome {
    bool cancelled = false;
    bool published = false;
    FinishedField finished;
  };
  void run();
  void insert(Entry entry);
  void finishRunning();                 // clears the running state; caller holds mutex_
  Result<Outcome> computeOnCpu(const FieldRequest& job, const WdtControl& control);
  Result<Outcome> computeOnDevice(const FieldRequest& job, const WdtControl& control);  // worker thread

  const Volume& volume_;
  const LabelMap& labels_;
  const std::size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable changed_;  // an entry was cached or a computation ended (waitFor)
  std::optional<FieldRequest> queued_;
  std::deque<FieldRequest> prefetches_;  // front first; taken only while queued_ is empty
  std::vector<std::string> pinned_;      // keys of the last prefetch list: not evicted while listed
  bool runningPrefetch_ = false;         // the running computation is a prefetch
  bool prefetchesHeld_ = false;          // holdPrefetches
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
  bool deviceLabelsStale_ = false;       // under mutex_: updateLabels ran since the device copy was made
  bool deviceBroken_ = false;            // worker thread only: a CUDA failure under auto, stay on the CPU
  std::string deviceWarning_;            // worker thread only: why, for the next result
  std::vector<FinishedField> finished_;
  std::thread thread_;
};

}  // namespace at::wdt
