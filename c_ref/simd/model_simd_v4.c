/* model_simd_v4.c — model_simd.c built a second time, for x86-64-v4 (AVX-512) with 512-bit
 * vectors (Makefile, SIMD_V4_CFLAGS): the same source and arithmetic, 16 floats or 8
 * doubles a vector and libmvec's AVX-512 functions (_ZGVeN16…). Its exported names end in
 * _v4; backend_cpu.c calls it through hb_simd_model_v4 only on a CPU that has AVX-512
 * (docs/cpu_simd.md, "Two builds"). */
#define hb_simd_init_block_f32 hb_simd_init_block_f32_v4
#define hb_simd_init_block_f64 hb_simd_init_block_f64_v4
#define hb_simd_wind_block_f32 hb_simd_wind_block_f32_v4
#define hb_simd_wind_block_f64 hb_simd_wind_block_f64_v4
#define hb_simd_collide_block_f32 hb_simd_collide_block_f32_v4
#define hb_simd_collide_block_f64 hb_simd_collide_block_f64_v4
#define hb_simd_wind_collide_block_f32 hb_simd_wind_collide_block_f32_v4
#define hb_simd_wind_collide_block_f64 hb_simd_wind_collide_block_f64_v4
#define hb_simd_isa hb_simd_isa_v4
#define HB_SIMD_MODEL_FNS hb_simd_model_v4
#if !defined(__AVX512F__)
#error "model_simd_v4.c must be compiled for x86-64-v4 (Makefile SIMD_V4_CFLAGS)"
#endif
#include "simd/model_simd.c"
