// malloc's settings for a paged build (`fragg_map build --page-store`): its memory is the
// budget's blocks plus what the allocator keeps, and the paging rounds free records and lists
// of tens of kilobytes among long-lived blocks on every thread's arena.
#pragma once

namespace fragg::cli {

/// Sets glibc's malloc for a paged build: one arena (the OpenMP threads' frees return to the
/// heap the next round reuses, not to one arena per thread each keeping its own) and
/// allocations of 1 MiB or more mapped on their own at a fixed threshold (freed, they go back
/// to the system; glibc otherwise raises the threshold as large blocks are freed). W4 paged on
/// CUDA (H100, 16 threads; the same two settings through MALLOC_ARENA_MAX and
/// MALLOC_MMAP_THRESHOLD_): peak RSS 1,168 -> 1,034 MiB, loop 3.52 -> 3.66 s; on the 2-core
/// machine (CPU, 2 threads) 972 / 943 -> 887 / 948 MiB, alternated (docs/benchmarks.md). False
/// where malloc refuses (not glibc): the build goes on with its defaults.
bool compactHeapForPaging();

}  // namespace fragg::cli
