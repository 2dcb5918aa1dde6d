/* SPDX-License-Identifier: MIT */
/* Fixed-point position control of one axis: the paper's P, PD and PID laws
 * (eq. 20-22), velocity estimation, trapezoidal set-points, output scaling
 * and saturation (eq. 19, 23-25).  No hardware access: the caller passes the
 * decoder readings in and writes the command out (servo.c), so the host unit
 * tests run exactly this code.
 *
 * Named fixed-point formats (value = integer / 2^n):
 *   *_q16  16 fractional bits (gains: PWM steps per count, per count/s, per count*s;
 *          positions: counts)
 *   *_q8   8 fractional bits (velocity: counts/s)
 *   *_q32  32 fractional bits, int64 (integrator: PWM steps)
 * The per-sample arithmetic divides only 32-bit numbers (docs/firmware.md,
 * "Control"): a 64-bit numerator over a 32-bit divisor goes through
 * tl_div64_32, two hardware divides; the only quotient computed per sample
 * is the edge-timestamp velocity (the profile carries its braking surplus).
 * PWM command: signed steps -1023..1023, the delta_PW of eq. (1); the PWM
 * block adds the dead zone PW0 and scales to PW_max in hardware. */
#ifndef TL_CONTROL_H
#define TL_CONTROL_H

#include <stdbool.h>
#include <stdint.h>

/* Code that runs with interrupts on and outside the control iteration (configuration,
 * start-up, command parsing) is compiled for size: the image with the iteration written
 * out per axis then keeps within the boot ROM's factory slot (docs/firmware.md, "Build").
 * Not code that runs with interrupts off, nor the commands with critical sections:
 * -Os copies structures byte by byte and would delay the control interrupt. */
#if defined(__riscv) && defined(__GNUC__) && !defined(__clang__)
#define TL_FOR_SIZE __attribute__((optimize("Os")))
#else
#define TL_FOR_SIZE
#endif
/* The control iteration: basic blocks laid out in source order (GCC's "simple" block
 * reordering) rather than by its guessed probabilities, which put the common path
 * behind taken forward branches (3 cycles each on the pipelined core, 1 when not taken;
 * docs/firmware.md, "Timing"). */
#define TL_LIKELY(x) __builtin_expect(!!(x), 1)
#define TL_UNLIKELY(x) __builtin_expect(!!(x), 0)
#if defined(__riscv) && defined(__GNUC__) && !defined(__clang__)
#define TL_HOT_LAYOUT __attribute__((optimize("reorder-blocks-algorithm=simple")))
#else
#define TL_HOT_LAYOUT
#endif

#define TL_LAW_OFF 0u
#define TL_LAW_P 1u
#define TL_LAW_PD 2u
#define TL_LAW_PID 3u
#define TL_PWM_FULL 1023
/* Profile limits per sample (q16 counts): speeds and their sum with one
 * acceleration step stay below 2^31.  16384 counts per sample is 655 000
 * counts/s at the longest period, far beyond the encoders. */
#define TL_CTL_VMAX_Q16_MAX 0x40000000
#define TL_CTL_AMAX_Q16_MAX 0x20000000
/* The profile's regimes: speeding up toward the target or cruising; braking onto it; braking
 * by amax past a target it could not stop for (then it turns back: TL_PROF_ACCEL). */
#define TL_PROF_ACCEL 0u
#define TL_PROF_BRAKE 1u
#define TL_PROF_OVERRUN 2u
/* Counts between two velocity samples beyond this are clamped to it (not physical). */
#define TL_CTL_DCOUNT_MAX 0x0FFFFFFF
/* Edge-timestamp speed of n counts over dt cycles, q8 counts/s (docs/firmware.md, "Control"):
 * N = n clk 2^8 brought below 2^32 by the smallest right shift k, then
 * v = (floor(N / 2^k) / dt) << k - one 32-bit divide.  For n < TL_CTL_SPEED_TAB the
 * shifted numerator and k come from this table, filled from the clock by tl_ctl_derived. */
#define TL_CTL_SPEED_TAB 64u
extern uint32_t tl_ctl_speed_m[TL_CTL_SPEED_TAB];
extern uint8_t tl_ctl_speed_k[TL_CTL_SPEED_TAB];

typedef struct {
    uint32_t law;
    int32_t kp_q16, kd_q16, ki_q16;
    int32_t deadband_q16;
    int32_t cmd_limit;
    uint32_t vel_mode;          /* 0: filtered Euler (paper), 1: edge timestamps */
    int32_t vmax_cps, amax_cps2;
    /* friction compensation (docs/firmware.md, "Friction compensation"); all 0: the plain law */
    int32_t fc_pos, fc_neg;     /* PWM steps added to a positive / the size of a negative command */
    int32_t izone_q16;          /* hunting guard: the integral is frozen while |e| <= this (counts q16) */
    int32_t kvff_q16;           /* velocity feed-forward: q16 PWM steps per count/s of the profile speed */
    int32_t dither_amp;         /* square-wave dither, PWM steps (0: off) ... */
    int32_t dither_half;        /* ... and its half-period, samples (>= 1) */
    int32_t kaff_q16;           /* acceleration feed-forward: q16 PWM steps per count/s^2 of the profile */
} tl_ctl_params_t;

/* What the parameters and the period give (tl_ctl_derived): computed apart
 * from the state, so a caller can compute it with interrupts on and hand it
 * to the control iteration in one short copy (tl_ctl_apply). */
typedef struct {
    int64_t ki_dt_q32;          /* PWM steps q32 added per count of error per sample */
    int32_t ki_e_max;           /* |e_q16| clamp that keeps ki_dt_q32 * e below 2^61 */
    int64_t lim_q32;            /* cmd_limit, q32: the integrator's clamp */
    uint32_t friction;          /* any friction-compensation parameter set: the default law tests only this */
    int64_t sat_hi_q16, sat_lo_q16;   /* the command's saturation, as bounds of u_q16 + 2^15 */
    int32_t vmax_q16;           /* counts per sample, q16, 1 .. TL_CTL_VMAX_Q16_MAX */
    int32_t amax_q16;           /* counts per sample^2, q16, 1 .. TL_CTL_AMAX_Q16_MAX */
    uint64_t s_vmax;            /* S(vmax_q16): the distance braking by amax_q16 covers after a sample at vmax (control_step.h) */
    int32_t euler_k;            /* Euler difference: q8 counts/s per count per sample, round(2^8 1e6 / T_us) */
    uint64_t clk_q8;            /* decoder clock, q8: counts/s q8 = counts * clk_q8 / cycles */
    uint32_t bound_m;           /* the standstill bound's numerator and shift: tl_ctl_speed_m/k[1] */
    uint32_t bound_k;
    uint32_t period_us;
    uint32_t clk_hz;
} tl_ctl_derived_t;

typedef struct {
    tl_ctl_derived_t d;
    /* state */
    int64_t sp_q16;             /* set-point, counts q16 */
    int64_t target_q16;
    int32_t prof_v_q16;         /* profile speed, counts per sample q16 (signed) */
    int32_t prof_a_q16;         /* the profile speed's change over the last sample, counts per sample^2 q16
                                   (signed: + speeding up toward +, - braking it; 0 at rest and on landing) */
    bool moving;
    /* the profile's plan (control_step.h profile, profile_plan): */
    uint32_t prof_st;           /* TL_PROF_ACCEL, _BRAKE or _OVERRUN */
    int32_t prof_s;             /* toward the target: 0 up, -1 down */
    int32_t prof_e32;           /* braking surplus E = d - S(v), counts q16 (d while moving away; < 0 in */
    int64_t prof_eres;          /* OVERRUN), as prof_eres + prof_e32: 0 <= prof_e32 < 2^31 takes each sample's
                                   step in 32 bits, refilled from prof_eres >= 0 when it runs out */
    uint32_t prof_b;            /* BRAKE: the braking speed so far, and the two speeds still to merge in */
    uint32_t prof_p1, prof_p2;
    int64_t integ_q32;
    int32_t sat_sign;           /* the last output hit +cmd_limit (1), -cmd_limit (-1), neither (0) */
    int32_t vel_q8;             /* velocity estimate, counts/s q8 */
    int32_t pos_prev;
    int32_t pos_ref;            /* position and decoder time of the last sample that saw a count */
    uint32_t t_ref;
    bool moved_last;            /* the previous sample saw a count */
    int32_t err_counts;         /* last error (rounded counts), for telemetry */
    uint32_t dither_n;          /* samples into the dither's period: + while < DITHER_HALF, - after */
} tl_ctl_t;

void tl_ctl_reset(tl_ctl_t *c, int32_t pos, uint32_t t_now);
/* tl_ctl_derived (slow: divisions) then tl_ctl_apply (a copy and one divide). */
void tl_ctl_derive(tl_ctl_t *c, const tl_ctl_params_t *p, uint32_t period_us, uint32_t clk_hz);
void tl_ctl_derived(tl_ctl_derived_t *d, const tl_ctl_params_t *p, uint32_t period_us, uint32_t clk_hz);
void tl_ctl_apply(tl_ctl_t *c, const tl_ctl_derived_t *d);
/* One sample: update velocity from (pos, edge_time, now) in decoder clock
 * cycles, advance the profile, run the law.  Returns the PWM command. */
int32_t tl_ctl_step(tl_ctl_t *c, const tl_ctl_params_t *p, int32_t pos, uint32_t edge_time, uint32_t now,
                    uint32_t interval, bool run_law);
void tl_ctl_move(tl_ctl_t *c, int32_t target, bool trapezoid);
void tl_ctl_hold(tl_ctl_t *c, int32_t pos);

/* floor(n / d) for a 64-bit n and 32-bit d > 0 whose quotient fits 32 bits
 * (n >> 32 < d), with 32-bit hardware divides only; UINT32_MAX if it does not fit. */
uint32_t tl_div64_32(uint64_t n, uint32_t d);
/* n >> k, k the smallest shift that brings n below 2^32 (tl_ctl_speed_m, edge_speed). */
uint32_t tl_speed_numerator(uint64_t n, uint32_t *k);

/* Physical <-> raw gains: micro N m per rad (per rad/s, per rad s) <-> q16 PWM steps per
 * count (per count/s, per count*s), through tau_max (PWM 1023) and counts per screw turn. */
int32_t tl_gain_raw_from_phys(int32_t micro, int32_t tau_max_mnm, int32_t counts_per_rev);
int32_t tl_gain_phys_from_raw(int32_t raw, int32_t tau_max_mnm, int32_t counts_per_rev);

#endif
