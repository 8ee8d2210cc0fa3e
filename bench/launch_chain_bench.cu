// What one link of a chain of dependent kernel launches costs on this GPU, without the sweep's
// work: a CUDA graph of L launches of a near-empty kernel (each block reads and writes one value a
// thread), replayed and timed with events. Shapes of the WDT sweep groups: 128 or 512 blocks of
// 512 threads (256³ and 512³). Chained plainly (each launch starts when the previous completes)
// and with programmatic dependent launch (the next grid's blocks start early and wait in
// griddepcontrol.wait, as the sweep kernels do). Standalone: nvcc -O3 -arch=sm_90 launch_chain_bench.cu
#include <cuda_runtime.h>

#include <algorithm>
#include <cstdio>
#include <vector>

#define CK(x)                                                                    \
  do {                                                                           \
    cudaError_t e_ = (x);                                                        \
    if (e_ != cudaSuccess) {                                                     \
      std::fprintf(stderr, "%s: %s\n", #x, cudaGetErrorString(e_));              \
      return 1;                                                                  \
    }                                                                            \
  } while (0)

__global__ void link(float* buf, int pdl) {
  const int i = blockIdx.x * blockDim.x + threadIdx.x;
  if (pdl) {
    asm volatile("griddepcontrol.wait;" ::: "memory");
    asm volatile("griddepcontrol.launch_dependents;" ::: "memory");
  }
  buf[i] = __ldcg(buf + i) + 1.0f;
}

int main() {
  const int links = 192, reps = 20;
  float* buf = nullptr;
  CK(cudaMalloc(&buf, sizeof(float) * 512 * 512));
  CK(cudaMemset(buf, 0, sizeof(float) * 512 * 512));
  cudaStream_t s;
  CK(cudaStreamCreateWithFlags(&s, cudaStreamNonBlocking));
  cudaEvent_t a, b;
  CK(cudaEventCreate(&a));
  CK(cudaEventCreate(&b));
  for (int blocks : {128, 512}) {
    for (int pdl : {0, 1}) {
      cudaLaunchConfig_t config{};
      config.gridDim = dim3(blocks);
      config.blockDim = dim3(512);
      config.stream = s;
      cudaLaunchAttribute attribute{};
      attribute.id = cudaLaunchAttributeProgrammaticStreamSerialization;
      attribute.val.programmaticStreamSerializationAllowed = 1;
      config.attrs = &attribute;
      config.numAttrs = pdl;
      cudaGraph_t graph;
      cudaGraphExec_t exec;
      CK(cudaStreamBeginCapture(s, cudaStreamCaptureModeThreadLocal));
      for (int l = 0; l < links; ++l) CK(cudaLaunchKernelEx(&config, link, buf, pdl));
      CK(cudaStreamEndCapture(s, &graph));
      CK(cudaGraphInstantiate(&exec, graph, 0));
      std::vector<float> ms;
      for (int r = 0; r < reps + 2; ++r) {
        CK(cudaEventRecord(a, s));
        CK(cudaGraphLaunch(exec, s));
        CK(cudaEventRecord(b, s));
        CK(cudaEventSynchronize(b));
        float t = 0;
        CK(cudaEventElapsedTime(&t, a, b));
        if (r >= 2) ms.push_back(t);
      }
      std::sort(ms.begin(), ms.end());
      std::printf("{\"bench\":\"launch_chain\",\"blocks\":%d,\"threads\":512,\"pdl\":%s,\"links\":%d,\"us_per_link_median\":%.3f}\n",
                  blocks, pdl ? "true" : "false", links, 1000.0 * ms[ms.size() / 2] / links);
      CK(cudaGraphExecDestroy(exec));
      CK(cudaGraphDestroy(graph));
    }
  }
  CK(cudaGetLastError());
  return 0;
}
