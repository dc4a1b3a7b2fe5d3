// FRAGG_HD marks functions shared by the CPU and CUDA backends. Under nvcc they compile for
// host and device; elsewhere the macro is empty.
#pragma once

#if defined(__CUDACC__)
#define FRAGG_HD __host__ __device__ __forceinline__
#else
#define FRAGG_HD inline
#endif
