// foveal/util/memory.cpp — glibc's malloc tuned for frame-sized buffers.
#include "foveal/util/memory.h"

#include <cstdlib>  // defines __GLIBC__ where the C library is glibc
#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace foveal {

void keep_freed_memory() {
#if defined(__GLIBC__)
  // Blocks below 32 MiB (glibc's largest threshold on 64-bit systems; a 1024×768 RGBA float image
  // is 12 MiB) come from the heap …
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 0x7fffffff);  // … and freed ones stay there for the next frame
#endif
}

void release_freed_memory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

}  // namespace foveal
