/* precision_end.h — removes the names of precision_f32.h / precision_f64.h. */
#undef REAL
#undef SFX
#undef MODEL
#undef SQRT
#undef SIN
#undef COS
#undef SINCOS
#undef ASIN
#undef ATAN2
#undef EPS
