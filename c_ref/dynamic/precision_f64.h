/* precision_f64.h — as precision_f32.h, for double. */
#define REAL double
#define RBITS uint64_t /* REAL's bits */
#define SFX(name) name##_f64
#define DMODEL hb_dyn_model_f64
#define WORLD hb_dyn_world_f64
#define SQRT sqrt
#define SIN sin
#define QTABLE(fr) ((fr)->q64)
#define PHASE(fr) ((fr)->phase64)
#define QSTART(fr) ((fr)->qs64)
#define POSES(fr) ((fr)->pose64)
#define BACKS(fr) ((fr)->back64)
