/* precision_end.h — removes the names of precision_f32.h / precision_f64.h. */
#undef REAL
#undef RBITS
#undef SFX
#undef DMODEL
#undef WORLD
#undef SQRT
#undef SIN
#undef QTABLE
#undef PHASE
#undef QSTART
#undef POSES
#undef BACKS
