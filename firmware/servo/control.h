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
 * PWM command: signed steps -1023..1023, the delta_PW of eq. (1); the PWM
 * block adds the dead zone PW0 and scales to PW_max in hardware. */
#ifndef TL_CONTROL_H
#define TL_CONTROL_H

#include <stdbool.h>
#include <stdint.h>

#define TL_LAW_OFF 0u
#define TL_LAW_P 1u
#define TL_LAW_PD 2u
#define TL_LAW_PID 3u
#define TL_PWM_FULL 1023

typedef struct {
    uint32_t law;
    int32_t kp_q16, kd_q16, ki_q16;
    int32_t deadband_q16;
    int32_t cmd_limit;
    uint32_t vel_mode;          /* 0: filtered Euler (paper), 1: edge timestamps */
    int32_t vmax_cps, amax_cps2;
} tl_ctl_params_t;

typedef struct {
    /* derived from params and the period (tl_ctl_derive) */
    int64_t ki_dt_q32;          /* PWM steps q32 added per count of error per sample */
    int64_t e_max_for_ki;       /* |e_q16| clamp that keeps ki_dt_q32 * e in int64 */
    int64_t vmax_q16;           /* counts per sample, q16 */
    int64_t amax_q16;           /* counts per sample^2, q16 (>= 1) */
    uint32_t period_us;
    uint32_t clk_hz;
    /* state */
    int64_t sp_q16;             /* set-point, counts q16 */
    int64_t target_q16;
    int64_t prof_v_q16;         /* profile speed, counts per sample q16 (signed) */
    bool moving;
    int64_t integ_q32;
    bool saturated;             /* last output hit cmd_limit */
    int32_t sat_sign;
    int32_t vel_q8;             /* velocity estimate, counts/s q8 */
    int32_t pos_prev;
    int32_t pos_ref;            /* position and decoder time of the last sample that saw a count */
    uint32_t t_ref;
    bool moved_last;            /* the previous sample saw a count */
    int32_t err_counts;         /* last error (rounded counts), for telemetry */
    int32_t cmd;                /* last PWM command */
} tl_ctl_t;

void tl_ctl_reset(tl_ctl_t *c, int32_t pos, uint32_t t_now);
void tl_ctl_derive(tl_ctl_t *c, const tl_ctl_params_t *p, uint32_t period_us, uint32_t clk_hz);
/* One sample: update velocity from (pos, edge_time, now) in decoder clock
 * cycles, advance the profile, run the law.  Returns the PWM command. */
int32_t tl_ctl_step(tl_ctl_t *c, const tl_ctl_params_t *p, int32_t pos, uint32_t edge_time, uint32_t now,
                    uint32_t interval, bool run_law);
void tl_ctl_move(tl_ctl_t *c, int32_t target, bool trapezoid);
void tl_ctl_hold(tl_ctl_t *c, int32_t pos);

/* Physical <-> raw gains: micro N m per rad (per rad/s, per rad s) <-> q16 PWM steps per
 * count (per count/s, per count*s), through tau_max (PWM 1023) and counts per screw turn. */
int32_t tl_gain_raw_from_phys(int32_t micro, int32_t tau_max_mnm, int32_t counts_per_rev);
int32_t tl_gain_phys_from_raw(int32_t raw, int32_t tau_max_mnm, int32_t counts_per_rev);

#endif
