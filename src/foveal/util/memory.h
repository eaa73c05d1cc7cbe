// foveal/util/memory.h — how the process keeps its memory between frames.
#pragma once

namespace foveal {

// Every frame allocates and frees image-sized buffers (G-buffers, pyramids, outputs). By default
// glibc maps each large block fresh from the kernel and unmaps it when freed, so the next frame
// pays a page fault per 4 KiB page again — on virtual machines that costs more than the blur
// itself. This keeps freed memory in the heap for reuse (no unmapping, no trimming). Call once at
// start-up; harmless where the C library is not glibc.
void keep_freed_memory();

// Give the heap's free memory back to the kernel now (glibc's malloc_trim): after a one-off
// phase that freed much more than the frames will use, such as loading a large mesh, so that it
// does not stay resident beside the BVH built next.
void release_freed_memory();

}  // namespace foveal
