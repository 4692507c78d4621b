#pragma once

// Functions marked RC_HD are compiled by both g++ (CPU backend) and nvcc (CUDA kernels), so every
// per-element step of the pipeline has exactly one implementation. Headers under device/ must not
// include Eigen or the standard library containers.
#if defined(__CUDACC__)
#define RC_HD __host__ __device__ __forceinline__
#else
#define RC_HD inline
#endif
