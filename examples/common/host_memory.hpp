#pragma once
// How the programs that fly many simulated missions ask the C library to keep the memory they
// free (adaptseg_calibrate, adaptseg_evaluate, adaptseg_cell_study). Each mission allocates its
// maps afresh (a pooled map holds every class's probability over the whole field); glibc's
// default hands each such block back to the system when it is freed and maps it again for the
// next, so every page of every map is faulted in and zeroed by the kernel once per mission. Kept,
// the next mission reuses the pages. Decisions and outputs are the same byte for byte; only the
// time changes (docs/benchmarks.md, "Calibration: freed memory kept"). The Python training does
// the same (adaptseg_tools.training.host_memory). A process-wide setting, so the programs'
// choice, never the library's. Not part of the library.

#include <cstdlib>
#include <cstring>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace adaptseg::examples {

/// Makes the C library serve large blocks from its heap and never give freed memory back to the
/// system (glibc: mallopt M_MMAP_MAX 0 and M_TRIM_THRESHOLD -1; mallopt(3)), so that memory freed
/// is reused by the next allocations. The process's resident size then stays at its peak: where
/// that matters more than time, the environment variable ADAPTSEG_KEEP_FREED_MEMORY=0 leaves the
/// C library's default. Returns false where it is left, where the C library has no such setting
/// (not glibc), or where it refuses it.
inline bool keep_freed_memory() noexcept {
  if (const char* v = std::getenv("ADAPTSEG_KEEP_FREED_MEMORY"); v != nullptr && std::strcmp(v, "0") == 0) return false;
#if defined(__GLIBC__)
  return mallopt(M_MMAP_MAX, 0) == 1 && mallopt(M_TRIM_THRESHOLD, -1) == 1;
#else
  return false;
#endif
}

}  // namespace adaptseg::examples
