// foveal/util/hd.h — FOVEAL_HD marks a function compiled for the CPU and, in the CUDA backend, the GPU.
//
// The per-pixel functions (camera rays, AO directions, the foveation model, BVH traversal,
// shading) are written once with this mark and called by both backends; outside nvcc it is empty.
#pragma once

#if defined(__CUDACC__)
#define FOVEAL_HD __host__ __device__
#else
#define FOVEAL_HD
#endif
