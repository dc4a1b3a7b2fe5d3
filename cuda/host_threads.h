// How many threads the CUDA backend's host-side copies use (CudaParams::host_threads).
#pragma once

#include <omp.h>

namespace fragg::cuda {

/// `requested` threads, or every core for 0.
inline int hostThreads(int requested) { return requested > 0 ? requested : omp_get_max_threads(); }

}  // namespace fragg::cuda
