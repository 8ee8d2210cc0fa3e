// RAII wrappers and error checking for the CUDA runtime, private to cuda/src (nothing outside this
// folder sees cudaError_t). Every runtime call goes through `check`, which turns a failure into an
// at::Error naming the call and the runtime's message ("cudaMalloc(268435456 bytes): out of memory").
#pragma once

#include <cuda_runtime.h>

#include <cstddef>
#include <string>
#include <utility>

#include "core/error.h"

namespace at::cuda {

// Success, or an Error "<what>: <cudaGetErrorString>". Clears the runtime's sticky-free last error.
inline Status check(cudaError_t code, const std::string& what) {
  if (code == cudaSuccess) return {};
  (void)cudaGetLastError();
  return fail(ErrorKind::Unavailable, "CUDA " + what + ": " + cudaGetErrorString(code));
}

// In a function returning Status or Result<T>: return the error of `expr` (a Status or Result) if
// it failed; AT_ASSIGN also moves its value into `var` otherwise.
#define AT_TRY(expr)                                          \
  do {                                                        \
    if (auto at_status_ = (expr); !at_status_)                \
      return tl::unexpected(std::move(at_status_).error());   \
  } while (0)

#define AT_ASSIGN(var, expr)                                  \
  do {                                                        \
    auto at_made_ = (expr);                                   \
    if (!at_made_) return tl::unexpected(at_made_.error());   \
    var = std::move(*at_made_);                               \
  } while (0)

// Typed, move-only device allocation of `count` elements (uninitialised).
template <class T>
class DeviceBuffer {
 public:
  DeviceBuffer() = default;
  static Result<DeviceBuffer> allocate(std::size_t count) {
    DeviceBuffer buffer;
    if (count == 0) return buffer;
    void* raw = nullptr;
    const std::size_t bytes = count * sizeof(T);
    if (auto s = check(cudaMalloc(&raw, bytes), "cudaMalloc(" + std::to_string(bytes) + " bytes)"); !s) {
      return tl::unexpected(s.error());
    }
    buffer.data_ = static_cast<T*>(raw);
    buffer.count_ = count;
    return buffer;
  }
  ~DeviceBuffer() { reset(); }
  DeviceBuffer(const DeviceBuffer&) = delete;
  DeviceBuffer& operator=(const DeviceBuffer&) = delete;
  DeviceBuffer(DeviceBuffer&& other) noexcept
      : data_(std::exchange(other.data_, nullptr)), count_(std::exchange(other.count_, 0)) {}
  DeviceBuffer& operator=(DeviceBuffer&& other) noexcept {
    if (this != &other) {
      reset();
      data_ = std::exchange(other.data_, nullptr);
      count_ = std::exchange(other.count_, 0);
    }
    return *this;
  }

  T* get() { return data_; }
  const T* get() const { return data_; }
  std::size_t size() const { return count_; }
  std::size_t bytes() const { return count_ * sizeof(T); }

 private:
  void reset() {
    if (data_) cudaFree(data_);  // cannot fail for a pointer cudaMalloc returned
    data_ = nullptr;
    count_ = 0;
  }
  T* data_ = nullptr;
  std::size_t count_ = 0;
};

// Page-locked host memory: asynchronous read-backs (the per-pass "changed" flag), transfer staging.
template <class T>
class PinnedBuffer {
 public:
  PinnedBuffer() = default;
  static Result<PinnedBuffer> allocate(std::size_t count) {
    PinnedBuffer buffer;
    void* raw = nullptr;
    if (auto s = check(cudaMallocHost(&raw, count * sizeof(T)), "cudaMallocHost"); !s) {
      return tl::unexpected(s.error());
    }
    buffer.data_ = static_cast<T*>(raw);
    return buffer;
  }
  ~PinnedBuffer() {
    if (data_) cudaFreeHost(data_);
  }
  PinnedBuffer(const PinnedBuffer&) = delete;
  PinnedBuffer& operator=(const PinnedBuffer&) = delete;
  PinnedBuffer(PinnedBuffer&& o) noexcept : data_(std::exchange(o.data_, nullptr)) {}
  PinnedBuffer& operator=(PinnedBuffer&& o) noexcept {
    std::swap(data_, o.data_);
    return *this;
  }
  T* get() { return data_; }

 private:
  T* data_ = nullptr;
};

// A non-blocking stream, destroyed with the object.
class Stream {
 public:
  Stream() = default;
  static Result<Stream> create() {
    Stream stream;
    if (auto s = check(cudaStreamCreateWithFlags(&stream.stream_, cudaStreamNonBlocking), "cudaStreamCreate"); !s) {
      return tl::unexpected(s.error());
    }
    return stream;
  }
  ~Stream() {
    if (stream_) cudaStreamDestroy(stream_);
  }
  Stream(const Stream&) = delete;
  Stream& operator=(const Stream&) = delete;
  Stream(Stream&& o) noexcept : stream_(std::exchange(o.stream_, nullptr)) {}
  Stream& operator=(Stream&& o) noexcept {
    std::swap(stream_, o.stream_);
    return *this;
  }
  cudaStream_t get() const { return stream_; }
  Status synchronize() const { return check(cudaStreamSynchronize(stream_), "cudaStreamSynchronize"); }

 private:
  cudaStream_t stream_ = nullptr;
};

// A timing event.
class Event {
 public:
  Event() = default;
  static Result<Event> create(unsigned flags = cudaEventDefault) {
    Event event;
    if (auto s = check(cudaEventCreateWithFlags(&event.event_, flags), "cudaEventCreate"); !s) {
      return tl::unexpected(s.error());
    }
    return event;
  }
  ~Event() {
    if (event_) cudaEventDestroy(event_);
  }
  Event(const Event&) = delete;
  Event& operator=(const Event&) = delete;
  Event(Event&& o) noexcept : event_(std::exchange(o.event_, nullptr)) {}
  Event& operator=(Event&& o) noexcept {
    std::swap(event_, o.event_);
    return *this;
  }
  Status record(const Stream& stream) { return check(cudaEventRecord(event_, stream.get()), "cudaEventRecord"); }
  Status synchronize() const { return check(cudaEventSynchronize(event_), "cudaEventSynchronize"); }
  // Milliseconds from `start` to this event; both must have completed.
  Result<float> millisecondsSince(const Event& start) const {
    float ms = 0;
    if (auto s = check(cudaEventElapsedTime(&ms, start.event_, event_), "cudaEventElapsedTime"); !s) {
      return tl::unexpected(s.error());
    }
    return ms;
  }

 private:
  cudaEvent_t event_ = nullptr;
};

// A captured CUDA graph, instantiated: one pass's launches replayed with one call.
class GraphExec {
 public:
  GraphExec() = default;
  // Captures what `enqueue(stream)` puts on `stream` and instantiates it.
  template <class Enqueue>
  static Result<GraphExec> capture(const Stream& stream, Enqueue&& enqueue) {
    if (auto s = check(cudaStreamBeginCapture(stream.get(), cudaStreamCaptureModeThreadLocal), "cudaStreamBeginCapture");
        !s) {
      return tl::unexpected(s.error());
    }
    const Status enqueued = enqueue(stream.get());
    cudaGraph_t graph = nullptr;
    const cudaError_t ended = cudaStreamEndCapture(stream.get(), &graph);
    if (!enqueued) {
      if (graph) cudaGraphDestroy(graph);
      return tl::unexpected(enqueued.error());
    }
    if (auto s = check(ended, "cudaStreamEndCapture"); !s) return tl::unexpected(s.error());
    GraphExec exec;
    const cudaError_t made = cudaGraphInstantiate(&exec.exec_, graph, 0);
    cudaGraphDestroy(graph);
    if (auto s = check(made, "cudaGraphInstantiate"); !s) return tl::unexpected(s.error());
    return exec;
  }
  ~GraphExec() {
    if (exec_) cudaGraphExecDestroy(exec_);
  }
  GraphExec(const GraphExec&) = delete;
  GraphExec& operator=(const GraphExec&) = delete;
  GraphExec(GraphExec&& o) noexcept : exec_(std::exchange(o.exec_, nullptr)) {}
  GraphExec& operator=(GraphExec&& o) noexcept {
    std::swap(exec_, o.exec_);
    return *this;
  }
  Status launch(const Stream& stream) const { return check(cudaGraphLaunch(exec_, stream.get()), "cudaGraphLaunch"); }

 private:
  cudaGraphExec_t exec_ = nullptr;
};

}  // namespace at::cuda
