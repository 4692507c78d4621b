#pragma once

// Functions marked RC_HD are compiled by both g++ (CPU backend) and nvcc (CUDA kernels), so every
// per-element step of the pipeline has exactly one implementation. Headers under device/ must not
// include Eigen or the standard library containers.
//
// RC_HD_CALL marks the few large ones that many call sites share (the exact phase's triangle tests
// and predicates, its tree walks): on the device they stay real calls, not forced inline, which
// would copy them into every caller (the kernel with the exact phase took nvcc over half an hour
// to compile fully inlined) and give each copy its own registers. On the host they are inline as
// usual, which leaves the choice to the compiler.
//
// RC_DEVICE marks what only device code may call where nvcc compiles it (a read of executor
// memory, which on a GPU the host cannot dereference), so that a host-side call fails to compile
// in the CUDA build even though the host executor, compiled by g++, runs the same code.
#if defined(__CUDACC__)
#define RC_HD __host__ __device__ __forceinline__
#define RC_HD_CALL __host__ __device__ __noinline__
#define RC_DEVICE __device__ __forceinline__
#else
#define RC_HD inline
#define RC_HD_CALL inline
#define RC_DEVICE inline
#endif

// RC_ROLLED_LOOP before a loop keeps nvcc from unrolling it (on the host, nothing): an unrolled
// search holds several iterations' loads at once, registers a whole kernel then pays for.
#if defined(__CUDA_ARCH__)
#define RC_ROLLED_LOOP _Pragma("unroll 1")
#else
#define RC_ROLLED_LOOP
#endif

namespace rastercheck::device
{
/** \brief Lowers *address to value atomically (the per-pair "first hit pixel" reduction, the first
    part of a split walk to find a contact). */
RC_HD void atomicMinimum(unsigned long long *address, unsigned long long value)
{
#if defined(__CUDA_ARCH__)
    atomicMin(address, value);
#else
    unsigned long long current = __atomic_load_n(address, __ATOMIC_RELAXED);
    while (value < current &&
           !__atomic_compare_exchange_n(address, &current, value, true, __ATOMIC_RELAXED, __ATOMIC_RELAXED))
    {
    }
#endif
}

/** \brief Reads a value other threads lower with atomicMinimum while this one runs (a relaxed load:
    a stale value only delays what the reader would skip). */
RC_HD unsigned long long atomicLoad(const unsigned long long *address)
{
#if defined(__CUDA_ARCH__)
    return *static_cast<const volatile unsigned long long *>(address);
#else
    return __atomic_load_n(address, __ATOMIC_RELAXED);
#endif
}
}  // namespace rastercheck::device
