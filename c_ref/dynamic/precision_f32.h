/* precision_f32.h — the names the dynamic model's math is written in (dynamic/dynamics_impl.h,
 * simd/dynamics_simd_impl.h), for float; precision_end.h removes them. Included by the files
 * that instantiate the math (dynamic/dynamics_f32.c, simd/dynamics_simd.c). */
#define REAL float
#define RBITS uint32_t /* REAL's bits */
#define SFX(name) name##_f32
#define DMODEL hb_dyn_model_f32
#define WORLD hb_dyn_world_f32
#define SQRT sqrtf
#define SIN sinf
#define QTABLE(fr) ((fr)->q32)
#define PHASE(fr) ((fr)->phase32)
#define QSTART(fr) ((fr)->qs32)
#define POSES(fr) ((fr)->pose32)
#define BACKS(fr) ((fr)->back32)
