/* The solvers are inlined where they are called: in the lane rhs's AVX2 clone
 * they are then compiled for AVX2 too (a call from AVX code into SSE code
 * costs more than the solve: measured 2.2 us against 0.19 us for the 8 lanes
 * of a double pendulum). */
#if defined(__GNUC__)
#define MP_INLINE inline __attribute__((always_inline))
#else
#define MP_INLINE inline
#endif
#define MP_LANE_LOOP _Pragma("omp simd") for (int l = 0; l < MP_LANES; l++)
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 11 && defined(__x86_64__) && \
    defined(__GLIBC__)
#define MP_LANE_FN __attribute__((target_clones("arch=x86-64-v3", "default")))
#define MP_VEC1(f) __attribute__((__simd__("notinbranch"), const, nothrow)) \
    double mp_lane_##f(double) __asm__(#f);
#define MP_VEC2(f) __attribute__((__simd__("notinbranch"), const, nothrow)) \
    double mp_lane_##f(double, double) __asm__(#f);
MP_VEC1(sin) MP_VEC1(cos) MP_VEC1(exp) MP_VEC1(log) MP_VEC2(pow)
#if __GLIBC_PREREQ(2, 35)
MP_VEC1(tan) MP_VEC1(asin) MP_VEC1(acos) MP_VEC1(atan) MP_VEC2(atan2) MP_VEC1(sinh)
MP_VEC1(cosh) MP_VEC1(tanh) MP_VEC1(asinh) MP_VEC1(acosh) MP_VEC1(atanh)
#define MP_LANE_NEW 0
#else
#define MP_LANE_NEW 1
#endif
#else
#define MP_LANE_FN
#define MP_LANE_NEW 1
#define mp_lane_sin sin
#define mp_lane_cos cos
#define mp_lane_exp exp
#define mp_lane_log log
#define mp_lane_pow pow
#endif
#if MP_LANE_NEW
#define mp_lane_tan tan
#define mp_lane_asin asin
#define mp_lane_acos acos
#define mp_lane_atan atan
#define mp_lane_atan2 atan2
#define mp_lane_sinh sinh
#define mp_lane_cosh cosh
#define mp_lane_tanh tanh
#define mp_lane_asinh asinh
#define mp_lane_acosh acosh
#define mp_lane_atanh atanh
#endif
