/* dynamics_simd_v4.c — dynamics_simd.c built a second time, for x86-64-v4 (AVX-512) with
 * 512-bit vectors, as model_simd_v4.c: its exported names end in _v4, and backend_cpu.c
 * calls it through hb_simd_dyn_v4 only on a CPU that has AVX-512 (docs/cpu_simd.md). */
#define hb_simd_dyn_scratch_reals hb_simd_dyn_scratch_reals_v4
#define hb_simd_dyn_bend_rest_block_f32 hb_simd_dyn_bend_rest_block_f32_v4
#define hb_simd_dyn_bend_rest_block_f64 hb_simd_dyn_bend_rest_block_f64_v4
#define hb_simd_dyn_frame_block_f32 hb_simd_dyn_frame_block_f32_v4
#define hb_simd_dyn_frame_block_f64 hb_simd_dyn_frame_block_f64_v4
#define hb_simd_dyn_observe_f32 hb_simd_dyn_observe_f32_v4
#define hb_simd_dyn_observe_f64 hb_simd_dyn_observe_f64_v4
#define HB_SIMD_DYN_FNS hb_simd_dyn_v4
#if !defined(__AVX512F__)
#error "dynamics_simd_v4.c must be compiled for x86-64-v4 (Makefile SIMD_V4_CFLAGS)"
#endif
#include "simd/dynamics_simd.c"
